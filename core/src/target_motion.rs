//! The target's own motion in the world (the `J_n(q) ^W ψ̇_M` term of eq. 23 that the paper
//! leaves out), and the hand-over of a pose to a later time.
//!
//! Every estimate `^CR ψ_M` is taken into the world through the arm's forward kinematics and
//! the hand-eye transform, `^W T_M = ^W T_H(q) · ^H T_CR · ^CR T_M` ([`world_pose`]). A
//! [`TargetFilter`] — a constant-velocity Kalman filter, one independent 2-state filter
//! `[x, ẋ]` per axis — estimates from that sequence
//!
//! - the linear velocity `^W ṙ_M` of the block's centre (three position axes), and
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
//! [`TargetFilterParams::trusted_speed_sd_m_s`] and [`TargetFilterParams::trusted_rate_sd_rad_s`],
//! and stays trusted until the filter restarts or is reset.
//!
//! [`TargetFilter::predict`] hands the pose over to a later time `t`: the last accepted
//! measurement moved by the trusted velocity over `t − t_capture`, seen from the camera at the
//! joint state of `t` (`q + q̇ (t − t_joints)`, forward kinematics).

use nalgebra::{Isometry3, Matrix3, Quaternion, Translation3, UnitQuaternion, Vector3};

use crate::kinematics::{Chain, JointSample};
use crate::pose::Psi;
use crate::status::Status;
use crate::{math, quat};

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

/// Tuning of a [`TargetFilter`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetFilterParams {
    /// Standard deviation of a position measurement (m).
    pub position_noise_m: f32,
    /// Standard deviation of an orientation measurement (rad, per axis).
    pub rotation_noise_rad: f32,
    /// Spectral density of the white acceleration noise of the position axes (m²/s³).
    pub acceleration_psd: f32,
    /// Spectral density of the white angular acceleration noise (rad²/s³).
    pub angular_acceleration_psd: f32,
    /// Prior standard deviation of the velocity after a reset (m/s).
    pub initial_speed_sd_m_s: f32,
    /// Prior standard deviation of the angular velocity after a reset (rad/s).
    pub initial_rate_sd_rad_s: f32,
    /// Innovation gate in standard deviations; a larger innovation on any axis is an outlier.
    pub gate_sigma: f32,
    /// Consecutive rejected measurements after which the filter restarts at the newest one.
    pub max_outliers: u16,
    /// Consecutive accepted updates needed before the velocity is trusted.
    pub converge_updates: u16,
    /// The velocity is trusted only while its standard deviation is below this (m/s).
    pub trusted_speed_sd_m_s: f32,
    /// The angular velocity is trusted only while its standard deviation is below this (rad/s).
    pub trusted_rate_sd_rad_s: f32,
    /// A fitness below this means the tracker lost the target: the filter resets.
    pub lost_fitness: f32,
    /// A time step above this (s) restarts the filter.
    pub max_gap_s: f32,
    /// Feedforward dead band: a speed below this (m/s) is fed forward as 0.
    pub deadband_m_s: f32,
    /// Feedforward dead band: an angular speed below this (rad/s) is fed forward as 0.
    pub deadband_rad_s: f32,
    /// Feedforward significance: the linear (angular) velocity is fed forward only when its
    /// length in standard deviations of its own estimate, `√(Σ vᵢ² / σᵢ²)`, reaches this — a
    /// velocity inside the filter's `significance_sigma`-σ ellipsoid around zero cannot be told
    /// from a target at rest, and feeding its noise forward drags the population along it.
    pub significance_sigma: f32,
}

impl TargetFilterParams {
    /// Defaults for the simulator's set-up (33 ms frames, estimates good to a few mm and a few
    /// mrad). The dead bands are about one frame's shift at the estimates' own noise floor
    /// (0.01 m/s · 33 ms = 0.33 mm; 0.05 rad/s · 33 ms = 1.7 mrad ≈ 0.0008 in ε).
    pub const DEFAULT: TargetFilterParams = TargetFilterParams {
        position_noise_m: 0.003,
        rotation_noise_rad: 0.02,
        acceleration_psd: 0.002,
        angular_acceleration_psd: 0.01,
        initial_speed_sd_m_s: 0.5,
        initial_rate_sd_rad_s: 2.0,
        gate_sigma: 6.0,
        max_outliers: 3,
        converge_updates: 10,
        trusted_speed_sd_m_s: 0.03,
        trusted_rate_sd_rad_s: 0.15,
        lost_fitness: 0.5,
        max_gap_s: 0.5,
        deadband_m_s: 0.01,
        deadband_rad_s: 0.05,
        significance_sigma: 2.0,
    };

    /// Checks that every value is finite and positive (counts at least 1).
    ///
    /// # Errors
    /// [`FilterParamsError`] naming the first bad field.
    pub fn validate(&self) -> Result<(), FilterParamsError> {
        let positive = [
            (self.position_noise_m, "position_noise_m"),
            (self.rotation_noise_rad, "rotation_noise_rad"),
            (self.acceleration_psd, "acceleration_psd"),
            (self.angular_acceleration_psd, "angular_acceleration_psd"),
            (self.initial_speed_sd_m_s, "initial_speed_sd_m_s"),
            (self.initial_rate_sd_rad_s, "initial_rate_sd_rad_s"),
            (self.gate_sigma, "gate_sigma"),
            (self.trusted_speed_sd_m_s, "trusted_speed_sd_m_s"),
            (self.trusted_rate_sd_rad_s, "trusted_rate_sd_rad_s"),
            (self.max_gap_s, "max_gap_s"),
        ];
        if let Some((_, name)) = positive.iter().find(|(v, _)| !(v.is_finite() && *v > 0.0)) {
            return Err(FilterParamsError(name));
        }
        let non_negative = [
            (self.lost_fitness, "lost_fitness"),
            (self.deadband_m_s, "deadband_m_s"),
            (self.deadband_rad_s, "deadband_rad_s"),
            (self.significance_sigma, "significance_sigma"),
        ];
        if let Some((_, name)) = non_negative.iter().find(|(v, _)| !(v.is_finite() && *v >= 0.0)) {
            return Err(FilterParamsError(name));
        }
        if self.max_outliers == 0 {
            return Err(FilterParamsError("max_outliers"));
        }
        if self.converge_updates == 0 {
            return Err(FilterParamsError("converge_updates"));
        }
        Ok(())
    }
}

/// A [`TargetFilterParams`] field is out of range (its name).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FilterParamsError(pub &'static str);

impl core::fmt::Display for FilterParamsError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "target filter parameter {} must be finite and positive", self.0)
    }
}

impl core::error::Error for FilterParamsError {}

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

/// One axis `[x, ẋ]` with covariance `[P₀₀, P₀₁, P₁₁]`.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Axis {
    x: f32,
    v: f32,
    p: [f32; 3],
}

impl Axis {
    fn start(x: f32, var_x: f32, var_v: f32) -> Self {
        Self { x, v: 0.0, p: [var_x, 0.0, var_v] }
    }

    /// `x ← x + v dt`, `P ← F P Fᵀ + Q(dt)` for white acceleration of spectral density `q`.
    fn predict(&mut self, dt: f32, q: f32) {
        let [a, b, c] = self.p;
        let dt2 = dt * dt;
        self.x += self.v * dt;
        self.p = [a + 2.0 * b * dt + c * dt2 + q * dt2 * dt / 3.0, b + c * dt + q * dt2 * 0.5, c + q * dt];
    }

    /// Whether innovation `y` is within `gate` standard deviations (`y² ≤ gate² S`).
    fn inlier(&self, y: f32, r: f32, gate: f32) -> bool {
        y * y <= gate * gate * (self.p[0] + r)
    }

    /// Measurement update with innovation `y` and measurement variance `r`.
    fn update(&mut self, y: f32, r: f32) {
        let [a, b, c] = self.p;
        let s = a + r;
        let (k0, k1) = (a / s, b / s);
        self.x += k0 * y;
        self.v += k1 * y;
        self.p = [(1.0 - k0) * a, (1.0 - k0) * b, c - k1 * b];
    }
}

/// The filter's state while it holds a track.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Track {
    pos: [Axis; 3],
    /// Error-state axes of the orientation (`x` is 0 between updates).
    rot: [Axis; 3],
    orientation: UnitQuaternion<f32>,
    time_us: u64,
    /// The last accepted measurement and its time (the base of [`TargetFilter::predict`]).
    last: Isometry3<f32>,
    last_time_us: u64,
    streak: u16,
    outliers: u16,
    /// Set once the track has converged; cleared only by a restart.
    converged: bool,
}

/// Constant-velocity Kalman filter of the target's world pose (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetFilter {
    params: TargetFilterParams,
    track: Option<Track>,
    last_outcome: Option<UpdateOutcome>,
    last_innovation: [f32; 6],
}

/// The pose handed over to a later time by [`TargetFilter::predict`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prediction {
    /// `^CR ψ_M` predicted at the requested time.
    pub psi: Psi,
    /// The target velocity used (zero unless [`Prediction::trusted`]).
    pub velocity: TargetVelocity,
    /// Whether the filter's velocity was trusted (otherwise the target is held still in the
    /// world and only the camera's motion is accounted for).
    pub trusted: bool,
    /// Capture time of the measurement the prediction starts from (µs).
    pub base_time_us: u64,
}

/// Why [`TargetFilter::predict`] could not predict.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum PredictError {
    /// The filter holds no track (never updated, reset, or lost).
    NoTrack,
    /// A joint position or velocity is NaN or infinite.
    NonFiniteJoint,
}

impl core::fmt::Display for PredictError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NoTrack => f.write_str("no target track to predict from"),
            Self::NonFiniteJoint => f.write_str("joint sample is not finite"),
        }
    }
}

impl core::error::Error for PredictError {}

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
        let outcome = self.update_inner(measured, time_us, fitness);
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
            self.track = None;
            self.last_outcome = Some(UpdateOutcome::Lost);
            return UpdateOutcome::Lost;
        }
        self.update(measured, time_us, fitness)
    }

    /// Feeds the tracker's estimate `psi` (with its `fitness` and `status`) of the frame captured
    /// with `joints`: the estimate in the world frame ([`world_pose`] of `chain` at `joints.q`
    /// and `flange_to_camera`) at `joints.time_us`, through
    /// [`TargetFilter::update_with_status`]. The tracker feeds its own filter with this call;
    /// a board that receives only the estimates feeds its copy with the same call on the same
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
        let world = world_pose(chain, &joints.q, flange_to_camera, psi);
        self.update_with_status(&world, joints.time_us, fitness, status)
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

    fn update_inner(&mut self, measured: &Isometry3<f32>, time_us: u64, fitness: f32) -> UpdateOutcome {
        // A fitness drop stands for a lost target here; `update_with_status` also resets on the
        // tracker's status.
        let found = fitness >= self.params.lost_fitness; // false for NaN
        if !found || !finite(measured) {
            self.track = None;
            return UpdateOutcome::Lost;
        }
        let Some(track) = self.track.as_mut() else {
            self.start(measured, time_us);
            return UpdateOutcome::Started;
        };
        let dt = if time_us >= track.time_us { (time_us - track.time_us) as f32 * 1e-6 } else { -1.0 };
        if !(dt >= 0.0 && dt <= self.params.max_gap_s) {
            self.start(measured, time_us);
            return UpdateOutcome::Started;
        }
        let p = &self.params;
        let (r_pos, r_rot) = (p.position_noise_m * p.position_noise_m, p.rotation_noise_rad * p.rotation_noise_rad);
        let mut predicted = *track;
        predicted.pos.iter_mut().for_each(|a| a.predict(dt, p.acceleration_psd));
        predicted.rot.iter_mut().for_each(|a| a.predict(dt, p.angular_acceleration_psd));
        let turn = Vector3::new(predicted.rot[0].x, predicted.rot[1].x, predicted.rot[2].x);
        predicted.orientation = exp_rotation(&turn) * predicted.orientation;
        predicted.rot.iter_mut().for_each(|a| a.x = 0.0);
        predicted.time_us = time_us;

        let t = measured.translation.vector;
        let y_pos = [t.x - predicted.pos[0].x, t.y - predicted.pos[1].x, t.z - predicted.pos[2].x];
        let y_rot = log_rotation(&(measured.rotation * predicted.orientation.inverse()));
        self.last_innovation = [y_pos[0], y_pos[1], y_pos[2], y_rot.x, y_rot.y, y_rot.z];
        let inlier = predicted.pos.iter().zip(y_pos.iter()).all(|(a, y)| a.inlier(*y, r_pos, p.gate_sigma))
            && predicted.rot.iter().zip(y_rot.iter()).all(|(a, y)| a.inlier(*y, r_rot, p.gate_sigma));
        if !inlier {
            predicted.streak = 0;
            predicted.outliers = predicted.outliers.saturating_add(1);
            if predicted.outliers >= p.max_outliers {
                self.start(measured, time_us);
                return UpdateOutcome::Started;
            }
            *track = predicted;
            return UpdateOutcome::Rejected;
        }
        for (a, y) in predicted.pos.iter_mut().zip(y_pos.iter()) {
            a.update(*y, r_pos);
        }
        for (a, y) in predicted.rot.iter_mut().zip(y_rot.iter()) {
            a.update(*y, r_rot);
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
        predicted.converged |= predicted.streak >= p.converge_updates
            && predicted.pos.iter().all(|a| a.p[2] <= sv)
            && predicted.rot.iter().all(|a| a.p[2] <= sw);
        *track = predicted;
        UpdateOutcome::Accepted
    }

    fn start(&mut self, measured: &Isometry3<f32>, time_us: u64) {
        let p = &self.params;
        let (r_pos, r_rot) = (p.position_noise_m * p.position_noise_m, p.rotation_noise_rad * p.rotation_noise_rad);
        let (v0, w0) =
            (p.initial_speed_sd_m_s * p.initial_speed_sd_m_s, p.initial_rate_sd_rad_s * p.initial_rate_sd_rad_s);
        let t = measured.translation.vector;
        self.track = Some(Track {
            pos: [Axis::start(t.x, r_pos, v0), Axis::start(t.y, r_pos, v0), Axis::start(t.z, r_pos, v0)],
            rot: [Axis::start(0.0, r_rot, w0); 3],
            orientation: measured.rotation,
            time_us,
            last: *measured,
            last_time_us: time_us,
            streak: 0,
            outliers: 0,
            converged: false,
        });
    }

    /// Whether the velocity has converged (see the module docs).
    /// It stays trusted through single outliers until the filter restarts or is reset.
    pub fn is_trusted(&self) -> bool {
        self.track.as_ref().is_some_and(|t| t.converged)
    }

    /// The estimated `^W ψ̇_M`, whether trusted or not (`None` without a track).
    pub fn velocity_estimate(&self) -> Option<TargetVelocity> {
        self.track.as_ref().map(|t| TargetVelocity {
            v: Vector3::new(t.pos[0].v, t.pos[1].v, t.pos[2].v),
            w: Vector3::new(t.rot[0].v, t.rot[1].v, t.rot[2].v),
        })
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
        let part = |axes: &[Axis; 3], deadband: f32| {
            let v = Vector3::new(axes[0].v, axes[1].v, axes[2].v);
            let sigmas2: f32 = axes.iter().map(|a| a.v * a.v / a.p[2].max(f32::MIN_POSITIVE)).sum();
            let significant = sigmas2 >= p.significance_sigma * p.significance_sigma;
            if significant && v.dot(&v) >= deadband * deadband { v } else { Vector3::zeros() }
        };
        TargetVelocity { v: part(&track.pos, p.deadband_m_s), w: part(&track.rot, p.deadband_rad_s) }
    }

    /// Hands the pose over to time `t_us`: the last accepted estimate moved by the trusted
    /// velocity over `t − t_capture` (held still while not trusted), seen from the camera at
    /// the joint state extrapolated to `t` (`q + q̇ (t − joints.time_us)`).
    ///
    /// # Errors
    /// [`PredictError::NoTrack`] or [`PredictError::NonFiniteJoint`].
    pub fn predict<const DOF: usize>(
        &self,
        chain: &Chain<DOF>,
        flange_to_camera: &Isometry3<f32>,
        joints: &JointSample<DOF>,
        t_us: u64,
    ) -> Result<Prediction, PredictError> {
        let track = self.track.as_ref().ok_or(PredictError::NoTrack)?;
        if !joints.q.iter().chain(joints.qd.iter()).all(|v| v.is_finite()) {
            return Err(PredictError::NonFiniteJoint);
        }
        let trusted = self.is_trusted();
        let velocity =
            if trusted { self.velocity_estimate().unwrap_or(TargetVelocity::ZERO) } else { TargetVelocity::ZERO };
        let tau = seconds_between(track.last_time_us, t_us);
        let target = Isometry3::from_parts(
            Translation3::from(track.last.translation.vector + velocity.v * tau),
            exp_rotation(&(velocity.w * tau)) * track.last.rotation,
        );
        let dtj = seconds_between(joints.time_us, t_us);
        let q: [f32; DOF] = core::array::from_fn(|i| joints.q[i] + joints.qd[i] * dtj);
        let camera = chain.forward(&q) * flange_to_camera;
        let psi = Psi::from_isometry(&(camera.inverse() * target));
        Ok(Prediction { psi, velocity, trusted, base_time_us: track.last_time_us })
    }
}

impl Default for TargetFilter {
    fn default() -> Self {
        Self::with_defaults()
    }
}

/// `t1 − t0` in seconds (negative when `t1 < t0`).
fn seconds_between(t0_us: u64, t1_us: u64) -> f32 {
    if t1_us >= t0_us { (t1_us - t0_us) as f32 * 1e-6 } else { -((t0_us - t1_us) as f32 * 1e-6) }
}

fn finite(iso: &Isometry3<f32>) -> bool {
    iso.translation.vector.iter().chain(iso.rotation.coords.iter()).all(|v| v.is_finite())
}

/// Rotation matrix `^CR R_W` of a camera pose (for [`crate::feedforward::jn`]).
pub fn camera_from_world_rotation(camera: &Isometry3<f32>) -> Matrix3<f32> {
    quat::to_rotation_matrix(&camera.rotation).transpose()
}

#[cfg(test)]
mod tests {
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

    #[test]
    fn constant_velocity_is_recovered() {
        let (v, w) = (Vector3::new(0.0, 0.2, -0.05), Vector3::new(0.0, 0.1, 0.5));
        let mut f = TargetFilter::with_defaults();
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
        let mut f = TargetFilter::with_defaults();
        for k in 0..60 {
            f.update(&moving(k, v, Vector3::zeros()), k * DT_US, 0.95);
        }
        assert!(f.is_trusted());
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
        let mut f = TargetFilter::with_defaults();
        for k in 0..60 {
            f.update(&moving(k, v, Vector3::zeros()), k * DT_US, 0.95);
        }
        let before = f.velocity().unwrap();
        // A wild estimate (half a metre and 90° off) is rejected and changes no velocity.
        let mut wild = moving(60, v, Vector3::zeros());
        wild.translation.vector.x += 0.5;
        wild.rotation = exp_rotation(&Vector3::new(1.57, 0.0, 0.0)) * wild.rotation;
        assert_eq!(f.update(&wild, 60 * DT_US, 0.95), UpdateOutcome::Rejected);
        assert_eq!(f.velocity_estimate().unwrap(), before);
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
        let mut p = TargetFilterParams::DEFAULT;
        p.gate_sigma = 0.0;
        assert_eq!(TargetFilter::new(p), Err(FilterParamsError("gate_sigma")));
        p = TargetFilterParams::DEFAULT;
        p.significance_sigma = -1.0;
        assert_eq!(TargetFilter::new(p), Err(FilterParamsError("significance_sigma")));
        p = TargetFilterParams::DEFAULT;
        p.converge_updates = 0;
        assert_eq!(TargetFilter::new(p), Err(FilterParamsError("converge_updates")));
    }

    #[test]
    fn deadband_zeroes_slow_motion_only() {
        let mut f = TargetFilter::with_defaults();
        let (v, w) = (Vector3::new(0.005, 0.0, 0.0), Vector3::new(0.0, 0.0, 0.3));
        for k in 0..80 {
            f.update(&moving(k, v, w), k * DT_US, 0.95);
        }
        let ff = f.feedforward_velocity();
        assert_eq!(ff.v, Vector3::zeros());
        assert!((ff.w - w).norm() < 0.02);
    }

    #[test]
    fn noise_of_a_still_target_is_not_fed_forward_but_slow_real_motion_is() {
        // Estimates of a target at rest with uniform noise of ±5 mm and ±0.02 rad: the
        // filter's velocity wanders above the dead bands, but never reaches significance.
        let mut f = TargetFilter::with_defaults();
        let still = Vector3::zeros();
        let mut above_deadband = 0;
        for k in 0..600 {
            f.update(&noisy(moving(k, still, still), k, 0.005, 0.02), k * DT_US, 0.95);
            if let Some(vel) = f.velocity() {
                above_deadband += usize::from(vel.v.norm() >= TargetFilterParams::DEFAULT.deadband_m_s);
                assert_eq!(f.feedforward_velocity(), TargetVelocity::ZERO, "frame {k}: {vel:?}");
            }
        }
        assert!(above_deadband > 0, "the dead band alone would have let noise through");
        // A slow conveyor (0.05 m/s) with the same noise is fed forward once converged.
        let mut f = TargetFilter::with_defaults();
        let v = Vector3::new(0.0, 0.05, 0.0);
        for k in 0..200 {
            f.update(&noisy(moving(k, v, still), k, 0.005, 0.02), k * DT_US, 0.95);
        }
        assert!((f.feedforward_velocity().v - v).norm() < 0.02, "{:?}", f.feedforward_velocity());
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
        let mut f = TargetFilter::with_defaults();
        let no_joints = JointSample { q, qd, time_us: 0 };
        assert_eq!(f.predict(&PA10, &mount, &no_joints, 0), Err(PredictError::NoTrack));
        for k in 0..80 {
            f.update(&moving(k, v, w), k * DT_US, 0.95);
        }
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
}
