//! Position-based visual servoing (PBVS): drives the right camera to a desired pose relative
//! to the block from the tracker's estimate (beyond the paper, which only argues that its
//! feedforward keeps such a loop stable).
//!
//! The law knows nothing of the tracker, the arm or the simulator: plain poses and twists in,
//! a camera twist out, so the same [`Servo`] drives a real arm through its own Cartesian
//! velocity interface.
//!
//! ## Law (one [`Servo::update`])
//! With `^CR T_M` the block's pose in the camera at the command time (the estimate handed
//! over from its capture time, e.g. by `TargetFilter::predict`) and `^CR T_M*` the desired
//! one, the camera's pose error is the desired camera frame seen from the current one,
//!
//! ```text
//! ^C T_C* = ^CR T_M · (^CR T_M*)⁻¹ = (R_e, t_e)
//! v* = λ t_e + (v_M − ω_M × r)          (r: the block centre in Σ_CR)
//! ω* = λ θu(R_e) + ω_M
//! ```
//!
//! where `(v_M, ω_M)` is the block's own velocity expressed in `Σ_CR` (zero when unknown: the
//! loop then lags a moving block by `v_M / λ`). All velocities are the camera's, in `Σ_CR`.
//! With a perfect measurement and no limits the error decays as `e^{−λt}`.
//!
//! ## Limits and safety
//! - `v*` and `ω*` are clamped to [`ServoLimits::max_speed_m_s`] and
//!   [`ServoLimits::max_rot_speed_rad_s`] (norms, direction kept).
//! - The command moves towards them by at most `max_accel · dt` per update (norm), so it never
//!   jumps, also when servoing starts or resumes.
//! - Without a measurement (the tracker does not hold the block) the target twist is zero:
//!   the camera decelerates to a stop at the same acceleration limits, within
//!   `max_speed / max_accel` seconds.
//!
//! Work per update is a fixed handful of products and one `atan2`/`sqrt` each; no loops.

use nalgebra::{Isometry3, Quaternion, UnitQuaternion, Vector3};

use crate::feedforward::CameraTwist;
use crate::math;

/// Speed and acceleration limits of the commanded camera twist.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoLimits {
    /// Largest linear speed of the camera origin (m/s).
    pub max_speed_m_s: f32,
    /// Largest angular speed (rad/s).
    pub max_rot_speed_rad_s: f32,
    /// Largest linear acceleration (m/s²).
    pub max_accel_m_s2: f32,
    /// Largest angular acceleration (rad/s²).
    pub max_rot_accel_rad_s2: f32,
}

/// Everything a [`Servo`] is built from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoConfig {
    /// `^CR T_M*`: the block's desired pose in the right camera frame.
    pub desired: Isometry3<f32>,
    /// Feedback gain `λ` (1/s), for position and orientation.
    pub gain: f32,
    /// Command limits.
    pub limits: ServoLimits,
}

/// A [`ServoConfig`] field is out of range.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum ServoConfigError {
    /// The desired pose has a non-finite component.
    Desired,
    /// The gain is not finite and positive.
    Gain,
    /// A limit is not finite and positive (its field name).
    Limit(&'static str),
}

impl core::fmt::Display for ServoConfigError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Desired => f.write_str("desired pose is not finite"),
            Self::Gain => f.write_str("gain must be finite and positive"),
            Self::Limit(name) => write!(f, "{name} must be finite and positive"),
        }
    }
}

impl core::error::Error for ServoConfigError {}

impl ServoConfig {
    /// Checks every field.
    ///
    /// # Errors
    /// [`ServoConfigError`] naming the first bad field.
    pub fn validate(&self) -> Result<(), ServoConfigError> {
        let d = &self.desired;
        if !d.translation.vector.iter().chain(d.rotation.coords.iter()).all(|v| v.is_finite()) {
            return Err(ServoConfigError::Desired);
        }
        if !(self.gain.is_finite() && self.gain > 0.0) {
            return Err(ServoConfigError::Gain);
        }
        let l = &self.limits;
        let limits = [
            (l.max_speed_m_s, "max_speed_m_s"),
            (l.max_rot_speed_rad_s, "max_rot_speed_rad_s"),
            (l.max_accel_m_s2, "max_accel_m_s2"),
            (l.max_rot_accel_rad_s2, "max_rot_accel_rad_s2"),
        ];
        match limits.iter().find(|(v, _)| !(v.is_finite() && *v > 0.0)) {
            Some((_, name)) => Err(ServoConfigError::Limit(name)),
            None => Ok(()),
        }
    }
}

/// What the law is given at a command time while the tracker holds the block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoInput {
    /// `^CR T_M`: the block's pose in the camera at the command time.
    pub pose: Isometry3<f32>,
    /// The block's own velocity in `Σ_CR` (velocity of its centre and angular velocity;
    /// [`CameraTwist::ZERO`] when unknown).
    pub target_velocity: CameraTwist,
}

/// The camera's pose error `^C T_C*` as translation and rotation vector (both in `Σ_CR`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseError {
    /// `t_e` (m).
    pub translation: Vector3<f32>,
    /// `θu` of `R_e` (rad).
    pub rotation: Vector3<f32>,
}

impl PoseError {
    /// `^C T_C* = ^CR T_M · (^CR T_M*)⁻¹` as translation and rotation vector.
    pub fn between(current: &Isometry3<f32>, desired: &Isometry3<f32>) -> Self {
        let e = current * desired.inverse();
        Self { translation: e.translation.vector, rotation: log_rotation(&e.rotation) }
    }

    /// `‖t_e‖` (m).
    pub fn translation_norm(&self) -> f32 {
        norm(&self.translation)
    }

    /// `‖θu‖`, the rotation angle (rad).
    pub fn rotation_norm(&self) -> f32 {
        norm(&self.rotation)
    }
}

/// What the servo is doing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ServoMode {
    /// Following a measurement.
    Servoing,
    /// No measurement; decelerating.
    Stopping,
    /// No measurement; at rest.
    Stopped,
}

/// The result of one [`Servo::update`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoOutput {
    /// The commanded camera twist in `Σ_CR` (within the limits).
    pub command: CameraTwist,
    /// The pose error of the measurement (`None` without one).
    pub error: Option<PoseError>,
    /// What the servo did.
    pub mode: ServoMode,
}

/// Why an update was refused (the servo's state is unchanged).
#[derive(Debug, Clone, Copy, PartialEq)]
#[non_exhaustive]
pub enum ServoStepError {
    /// `dt` is not finite and positive.
    BadDt(f32),
    /// The input pose or velocity has a non-finite component.
    NonFiniteInput,
}

impl core::fmt::Display for ServoStepError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::BadDt(dt) => write!(f, "time step {dt} s is not finite and positive"),
            Self::NonFiniteInput => f.write_str("servo input is not finite"),
        }
    }
}

impl core::error::Error for ServoStepError {}

/// The PBVS law with its last command (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Servo {
    config: ServoConfig,
    command: CameraTwist,
}

impl Servo {
    /// A servo at rest.
    ///
    /// # Errors
    /// [`ServoConfigError`] for an invalid configuration.
    pub fn new(config: ServoConfig) -> Result<Self, ServoConfigError> {
        config.validate()?;
        Ok(Self { config, command: CameraTwist::ZERO })
    }

    /// The configuration.
    pub fn config(&self) -> &ServoConfig {
        &self.config
    }

    /// The last command.
    pub fn command(&self) -> &CameraTwist {
        &self.command
    }

    /// The unlimited law `(v*, ω*)` for `input`, and its pose error.
    pub fn law(&self, input: &ServoInput) -> (CameraTwist, PoseError) {
        let err = PoseError::between(&input.pose, &self.config.desired);
        let (vm, wm) = (input.target_velocity.v, input.target_velocity.w);
        let r = input.pose.translation.vector;
        let lambda = self.config.gain;
        let v = err.translation * lambda + vm - wm.cross(&r);
        let w = err.rotation * lambda + wm;
        (CameraTwist { v, w }, err)
    }

    /// One command period of `dt_s` seconds: with `Some(input)` (the tracker holds the block)
    /// the command moves towards the clamped law, without it towards rest, in both cases by at
    /// most the acceleration limits times `dt_s`.
    ///
    /// # Errors
    /// [`ServoStepError`] for a bad `dt_s` or a non-finite input; the servo is then unchanged.
    pub fn update(&mut self, input: Option<&ServoInput>, dt_s: f32) -> Result<ServoOutput, ServoStepError> {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(ServoStepError::BadDt(dt_s));
        }
        let l = self.config.limits;
        let (target, error) = match input {
            Some(i) => {
                if !finite_input(i) {
                    return Err(ServoStepError::NonFiniteInput);
                }
                let (t, e) = self.law(i);
                let t =
                    CameraTwist { v: clamp_norm(&t.v, l.max_speed_m_s), w: clamp_norm(&t.w, l.max_rot_speed_rad_s) };
                (t, Some(e))
            }
            None => (CameraTwist::ZERO, None),
        };
        let prev = self.command;
        self.command = CameraTwist {
            v: prev.v + clamp_norm(&(target.v - prev.v), l.max_accel_m_s2 * dt_s),
            w: prev.w + clamp_norm(&(target.w - prev.w), l.max_rot_accel_rad_s2 * dt_s),
        };
        let mode = match (input, is_zero(&self.command)) {
            (Some(_), _) => ServoMode::Servoing,
            (None, false) => ServoMode::Stopping,
            (None, true) => ServoMode::Stopped,
        };
        Ok(ServoOutput { command: self.command, error, mode })
    }

    /// Sets the command to rest at once (e.g. after an emergency stop of the arm).
    pub fn halt(&mut self) {
        self.command = CameraTwist::ZERO;
    }
}

fn is_zero(t: &CameraTwist) -> bool {
    t.v.iter().chain(t.w.iter()).all(|x| *x == 0.0)
}

fn finite_input(i: &ServoInput) -> bool {
    let p = &i.pose;
    let t = &i.target_velocity;
    p.translation
        .vector
        .iter()
        .chain(p.rotation.coords.iter())
        .chain(t.v.iter())
        .chain(t.w.iter())
        .all(|v| v.is_finite())
}

fn norm(v: &Vector3<f32>) -> f32 {
    math::sqrt(v.dot(v))
}

/// `v` scaled down to norm `max` if longer (direction kept).
fn clamp_norm(v: &Vector3<f32>, max: f32) -> Vector3<f32> {
    let n = norm(v);
    if n > max { v * (max / n) } else { *v }
}

/// The rotation vector `θu` of the shortest rotation equal to `q`.
fn log_rotation(q: &UnitQuaternion<f32>) -> Vector3<f32> {
    let c: Quaternion<f32> = if q.w < 0.0 { -q.into_inner() } else { q.into_inner() };
    let e = c.imag();
    let n = norm(&e);
    if n < 1e-12 { e * 2.0 } else { e * (2.0 * math::atan2(n, c.w) / n) }
}

#[cfg(test)]
mod tests;
