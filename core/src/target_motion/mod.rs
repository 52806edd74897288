//! The target's own motion in the world (the `J_n(q) ^W ψ̇_M` term of eq. 23 that the paper
//! leaves out), and the hand-over of a pose to a later time.
//!
//! Every estimate `^CR ψ_M` is taken into the world through the arm's forward kinematics and
//! the hand-eye transform, `^W T_M = ^W T_H(q) · ^H T_CR · ^CR T_M` ([`world_pose`]). A
//! [`TargetFilter`] — two constant-velocity Kalman filters, one on the block's centre and one
//! on its orientation (an error state: the orientation is kept as a unit quaternion, the
//! innovation is the rotation vector `log(Q_meas · Q̂⁻¹)` in `Σ_W`) — estimates from that
//! sequence the block's velocity screw `^W ψ̇_M` in every direction, towards and away from the
//! cameras too. The tracker feeds it forward to the population as eq. 23's `J_n` term.
//!
//! **Depth is weighed as the cameras see it.** Stereo resolves the position across the line of
//! sight far better than along it. With an estimate's image noise `σ` (px,
//! [`TargetFilterParams::image_noise_px`]) and the rig's focal length `f` and baseline `b`
//! ([`Optics`]), a block at range `Z` is measured to `Z·σ/f` across the line of sight and to
//! `Z²·σ/(f·b)` along it. The position's measurement covariance is that ellipsoid turned into
//! the world, `R = σ⊥² I + (σ∥² − σ⊥²) u uᵀ` (`u` the unit line of sight), so the filter learns
//! a motion in depth from many estimates and a motion across the view from few. The
//! orientation's noise is `Z·σ/f` over the block's mean half-extent, per axis.
//!
//! **What the block may do** is said in physical units: the largest acceleration and angular
//! acceleration expected (the process noise), and the largest speed and angular speed when it
//! is first seen (the prior of a restart, so a block already moving when it is acquired is
//! followed from its first estimates). The velocity fed forward is the filter's estimate; there
//! is no trust threshold, dead band or switch. Whether it is real is left to the fitness: the
//! tracker moves its elite by the camera's motion alone (the hypothesis that the block stands
//! still) and every other individual by the filter's velocity as well, two copies of the elite
//! with and without the filter's turn among them, and the selection keeps whichever fits the
//! next frame better ([`crate::tracker::Tracker::step`]). Without that, a
//! noisy velocity fed forward to every individual drags the estimate along its own noise where
//! the fitness is flat (depth above all), and the filter reads that back as motion.
//!
//! **Restarts.** A time step backwards or longer than [`TargetFilterParams::max_gap_s`] restarts
//! the filter at the newest estimate; an estimate of a block the tracker does not hold
//! ([`Status::holds`]: searching or lost) resets it. No estimate is gated out as an outlier: a GA estimate's errors
//! are not Gaussian (it keeps its elite for frames, then jumps to a better individual), and a
//! gate sized for the camera model's noise rejects those jumps, restarts the filter and loses a
//! block in the middle of a reversal; a block that is really gone is the tracker's status to
//! say.
//!
//! Work per update is a fixed handful of 3 × 3 products (no loops over data), storage a few
//! dozen floats, and all transcendental functions go through [`crate::math`], so the filter is
//! bit-identical on host and board.
//!
//! [`TargetFilter::predict`] hands the pose over to a later time `t`, seen from the camera at the
//! joint state of `t` (`q + q̇ (t − t_joints)`, forward kinematics). **A manoeuvre is handed over
//! too.** The constant-velocity model learns a reversal only after it, and a servo handed its
//! velocity a frame or two later lags by the latency as well; so the filter also keeps Singer's
//! manoeuvring-target model of the centre (an acceleration state that decays over the manoeuvre
//! time [`TargetFilterParams::manoeuvre_s`], of standard deviation
//! [`TargetFilterParams::acceleration_sd`]), fed the same estimates, and the centre is handed
//! over with its mean motion; the orientation with the constant-velocity model's turn. The
//! velocity fed forward to the population stays the constant-velocity model's: an acceleration
//! state there reads the estimate's slow drift in depth as an acceleration (measured in
//! `docs/method.md`, "Hand-over of a manoeuvring block").

use nalgebra::{Isometry3, Matrix3, Quaternion, Translation3, UnitQuaternion, Vector3};

use crate::camera::StereoRig;
use crate::kinematics::{Chain, JointSample};
use crate::model::Block;
use crate::pose::Psi;
use crate::status::Status;
use crate::{math, quat};

mod kalman;
mod predict;
use crate::tuning::ConfigError;
pub use crate::tuning::TargetFilterParams;
use kalman::{CvFilter, SingerFilter};
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

/// What the camera model says of one estimate's precision: the rig's focal length and baseline
/// and the block's size (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Optics {
    /// Focal length (px).
    pub focal_px: f32,
    /// Stereo baseline (m).
    pub baseline_m: f32,
    /// The block's mean half-extent (m): the lever arm of a turn.
    pub radius_m: f32,
}

impl Optics {
    /// The evorec simulator's rig (800 px, 0.1 m) and the paper's block.
    pub const DEFAULT: Optics = Optics { focal_px: 800.0, baseline_m: 0.1, radius_m: 0.075 };

    /// The optics of `rig` (the right camera's mean focal length, the distance between the
    /// cameras) looking at `block`.
    pub fn of(rig: &StereoRig, block: &Block) -> Self {
        let b = rig.left_from_right.translation.vector;
        let [x, y, z] = block.size_m;
        Self {
            focal_px: 0.5 * (rig.right.fx() + rig.right.fy()),
            baseline_m: math::sqrt(b.dot(&b)),
            radius_m: (x + y + z) / 6.0,
        }
    }

    /// `(σ⊥, σ∥)`: the standard deviations (m) across and along the line of sight of a block
    /// at `range_m` seen with image noise `sigma_px`.
    pub fn position_noise(&self, range_m: f32, sigma_px: f32) -> (f32, f32) {
        let across = range_m * sigma_px / self.focal_px;
        (across, across * range_m / self.baseline_m)
    }
}

/// What one [`TargetFilter::update`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UpdateOutcome {
    /// The filter (re)started at this measurement (first one, after a reset or a time gap).
    Started,
    /// The measurement was accepted.
    Accepted,
    /// The target was lost: the filter was reset and holds no track.
    Lost,
}

/// The filter's state while it holds a track.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Track {
    pos: CvFilter,
    /// The manoeuvring model of the position, for the hand-over ([`TargetFilter::predict`]).
    ahead: SingerFilter,
    /// The orientation's error state (its position part is 0 between updates).
    rot: CvFilter,
    orientation: UnitQuaternion<f32>,
    time_us: u64,
    /// Accepted estimates since the (re)start, the starting one included.
    updates: u16,
}

/// Constant-velocity Kalman filter of the target's world pose (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TargetFilter {
    params: TargetFilterParams,
    optics: Optics,
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

/// The measurement covariances `(R_position, R_orientation)` of an estimate `measured` seen from
/// a camera at `camera_at` (world).
fn measurement_noise(
    params: &TargetFilterParams,
    optics: &Optics,
    measured: &Isometry3<f32>,
    camera_at: &Vector3<f32>,
) -> (Matrix3<f32>, Matrix3<f32>) {
    let sight = measured.translation.vector - camera_at;
    let range = math::sqrt(sight.dot(&sight));
    let (across, along) = optics.position_noise(range, params.image_noise_px);
    let u = if range > 1e-6 { sight / range } else { Vector3::zeros() };
    let i = Matrix3::<f32>::identity();
    let r_pos = i * (across * across) + u * u.transpose() * (along * along - across * across);
    let sd_rot = across / optics.radius_m;
    (r_pos, i * (sd_rot * sd_rot))
}

impl TargetFilter {
    /// An empty filter (no track) seeing through the default [`Optics`].
    ///
    /// # Errors
    /// [`ConfigError`] naming the first invalid parameter (`target.…`).
    pub fn new(params: TargetFilterParams) -> Result<Self, ConfigError> {
        params.validate()?;
        Ok(Self { params, ..Self::with_defaults() })
    }

    /// An empty filter with `params` (validated by the caller: a tracker's configuration is)
    /// seeing through `optics`.
    pub(crate) fn tuned(params: TargetFilterParams, optics: Optics) -> Self {
        Self { params, ..Self::with_defaults() }.with_optics(optics)
    }

    /// An empty filter with [`TargetFilterParams::DEFAULT`] and [`Optics::DEFAULT`].
    pub const fn with_defaults() -> Self {
        Self {
            params: TargetFilterParams::DEFAULT,
            optics: Optics::DEFAULT,
            track: None,
            last_outcome: None,
            last_innovation: [0.0; 6],
        }
    }

    /// Builder: the camera model (forgets the track). The tracker's filter has its rig's and
    /// block's ([`Optics::of`]); a board's copy must have the same.
    #[must_use]
    pub fn with_optics(mut self, optics: Optics) -> Self {
        self.optics = optics;
        self.track = None;
        self
    }

    /// The parameters.
    pub fn params(&self) -> &TargetFilterParams {
        &self.params
    }

    /// The camera model.
    pub fn optics(&self) -> &Optics {
        &self.optics
    }

    /// Replaces the parameters and forgets the track.
    ///
    /// # Errors
    /// [`ConfigError`] naming the first invalid parameter (the filter is then unchanged).
    pub fn set_params(&mut self, params: TargetFilterParams) -> Result<(), ConfigError> {
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

    /// Feeds one estimate `measured = ^W T_M` captured at `time_us` by a camera at `camera_at`
    /// (world): its noise is the camera model's for that line of sight (see the module docs).
    pub fn update(&mut self, measured: &Isometry3<f32>, camera_at: &Vector3<f32>, time_us: u64) -> UpdateOutcome {
        let outcome = self.update_inner(measured, camera_at, time_us);
        self.last_outcome = Some(outcome);
        outcome
    }

    /// What the last [`TargetFilter::update`] did (`None` before the first).
    pub fn last_outcome(&self) -> Option<UpdateOutcome> {
        self.last_outcome
    }

    /// Innovation of the last update: position (m, world) and rotation vector (rad, world).
    pub fn last_innovation(&self) -> [f32; 6] {
        self.last_innovation
    }

    /// Feeds the tracker's estimate `psi` (`^CR ψ_M`, with its `status`) of the frame captured
    /// with `joints`: the estimate taken into the world through `chain` at `joints.q` and
    /// `flange_to_camera` ([`world_pose`]) at `joints.time_us`. An estimate of a block that is
    /// not held ([`Status::holds`]) is no measurement of it (searching, or carried along after
    /// the block was lost), so the filter resets; an [`Status::Uncertain`] one is. The tracker feeds its own filter with this
    /// call; a board that receives only the estimates feeds its copy with the same call on the
    /// same numbers, so its predictions are the tracker's.
    pub fn update_from_estimate<const DOF: usize>(
        &mut self,
        chain: &Chain<DOF>,
        flange_to_camera: &Isometry3<f32>,
        joints: &JointSample<DOF>,
        psi: &Psi,
        status: Status,
    ) -> UpdateOutcome {
        if !status.holds() {
            self.track = None;
            self.last_outcome = Some(UpdateOutcome::Lost);
            return UpdateOutcome::Lost;
        }
        let camera = chain.forward(&joints.q) * flange_to_camera;
        self.update(&camera_to_world(&camera, psi), &camera.translation.vector, joints.time_us)
    }

    fn update_inner(&mut self, measured: &Isometry3<f32>, camera_at: &Vector3<f32>, time_us: u64) -> UpdateOutcome {
        if !finite(measured) || !camera_at.iter().all(|v| v.is_finite()) {
            self.track = None;
            return UpdateOutcome::Lost;
        }
        let (r_pos, r_rot) = measurement_noise(&self.params, &self.optics, measured, camera_at);
        let Some(track) = self.track.as_mut() else {
            self.start(measured, &r_pos, &r_rot, time_us);
            return UpdateOutcome::Started;
        };
        let dt = if time_us >= track.time_us { (time_us - track.time_us) as f32 * 1e-6 } else { -1.0 };
        if !(dt >= 0.0 && dt <= self.params.max_gap_s) {
            self.start(measured, &r_pos, &r_rot, time_us);
            return UpdateOutcome::Started;
        }
        let p = self.params;
        let mut next = *track;
        next.pos.predict(dt, p.acceleration_m_s2);
        next.ahead.predict(dt, math::exp(-dt / p.manoeuvre_s()), p.acceleration_sd());
        next.rot.predict(dt, p.angular_acceleration_rad_s2);
        next.orientation = exp_rotation(&next.rot.x) * next.orientation;
        next.rot.set_position(Vector3::zeros());
        next.time_us = time_us;

        let turn = log_rotation(&(measured.rotation * next.orientation.inverse()));
        let (pos_inn, rot_inn) =
            (next.pos.innovation(&measured.translation.vector, &r_pos), next.rot.innovation(&turn, &r_rot));
        let ahead_inn = next.ahead.innovation(&measured.translation.vector, &r_pos);
        let (Some(pos_inn), Some(rot_inn), Some(ahead_inn)) = (pos_inn, rot_inn, ahead_inn) else {
            self.start(measured, &r_pos, &r_rot, time_us);
            return UpdateOutcome::Started;
        };
        self.last_innovation = [pos_inn.y.x, pos_inn.y.y, pos_inn.y.z, rot_inn.y.x, rot_inn.y.y, rot_inn.y.z];
        next.pos.update(&pos_inn);
        next.ahead.update(&ahead_inn);
        let correction = next.rot.update(&rot_inn);
        next.orientation = exp_rotation(&correction) * next.orientation;
        next.rot.set_position(Vector3::zeros());
        next.updates = next.updates.saturating_add(1);
        *track = next;
        UpdateOutcome::Accepted
    }

    fn start(&mut self, measured: &Isometry3<f32>, r_pos: &Matrix3<f32>, r_rot: &Matrix3<f32>, time_us: u64) {
        let p = &self.params;
        self.track = Some(Track {
            pos: CvFilter::start(measured.translation.vector, r_pos, p.max_speed_m_s),
            ahead: SingerFilter::start(measured.translation.vector, r_pos, p.max_speed_m_s, p.acceleration_sd()),
            rot: CvFilter::start(Vector3::zeros(), r_rot, p.max_rate_rad_s),
            orientation: measured.rotation,
            time_us,
            updates: 1,
        });
    }

    /// Whether the velocity has been observed: the track holds at least two accepted
    /// estimates (one alone says nothing of the motion).
    pub fn is_trusted(&self) -> bool {
        self.track.as_ref().is_some_and(|t| t.updates >= 2)
    }

    /// The estimated `^W ψ̇_M` (`None` without a track).
    pub fn velocity_estimate(&self) -> Option<TargetVelocity> {
        self.track.as_ref().map(|t| TargetVelocity { v: t.pos.v, w: t.rot.v })
    }

    /// The velocity once observed ([`TargetFilter::is_trusted`]), else `None`.
    pub fn velocity(&self) -> Option<TargetVelocity> {
        if self.is_trusted() { self.velocity_estimate() } else { None }
    }

    /// The velocity to feed forward: the filter's once observed, zero before.
    pub fn feedforward_velocity(&self) -> TargetVelocity {
        self.velocity().unwrap_or(TargetVelocity::ZERO)
    }

    /// The manoeuvring model's acceleration of the block's centre (m/s², world) at the last
    /// update (`None` without a track): what [`TargetFilter::predict`] extrapolates with.
    pub fn acceleration_estimate(&self) -> Option<Vector3<f32>> {
        self.track.as_ref().map(|t| t.ahead.acc)
    }

    /// The filtered world pose `^W T_M` at the last update (`None` without a track).
    pub fn pose(&self) -> Option<Isometry3<f32>> {
        self.track.as_ref().map(|t| Isometry3::from_parts(Translation3::from(t.pos.x), t.orientation))
    }
}

impl Default for TargetFilter {
    fn default() -> Self {
        Self::with_defaults()
    }
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
