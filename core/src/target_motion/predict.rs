//! The hand-over of the target's pose to a later time ([`TargetFilter::predict`]).

use nalgebra::{Isometry3, Translation3, Vector3};

use super::{TargetFilter, TargetVelocity, exp_rotation};
use crate::kinematics::{Chain, JointSample};
use crate::pose::Psi;

/// The pose handed over to a later time by [`TargetFilter::predict`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prediction {
    /// `^CR ψ_M` predicted at the requested time.
    pub psi: Psi,
    /// The target velocity used (zero unless [`Prediction::trusted`]).
    pub velocity: TargetVelocity,
    /// Whether the filter's velocity had been observed (otherwise the target is held still in
    /// the world and only the camera's motion is accounted for).
    pub trusted: bool,
    /// Capture time of the last estimate the filter took (µs): the prediction starts there.
    pub base_time_us: u64,
}

error_enum! {
    /// Why [`TargetFilter::predict`] could not predict.
    pub enum PredictError {
        /// The filter holds no track (never updated, reset, or lost).
        NoTrack => "no target track to predict from",
        /// A joint position or velocity is NaN or infinite.
        NonFiniteJoint => "joint sample is not finite",
    }
}

impl TargetFilter {
    /// Hands the pose over to time `t_us`: the filtered pose moved by the filtered velocity
    /// over `τ = t − t_update` (held still until the velocity has been observed), seen from the
    /// camera at the joint state extrapolated to `t` (`q + q̇ (t − joints.time_us)`).
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
        let tau = seconds_between(track.time_us, t_us);
        let dtj = seconds_between(joints.time_us, t_us);
        let q: [f32; DOF] = core::array::from_fn(|i| joints.q[i] + joints.qd[i] * dtj);
        let camera = chain.forward(&q) * flange_to_camera;
        // The centre from the manoeuvring model once it has seen the motion; the turn from the
        // orientation's constant-velocity model.
        let w = self.feedforward_velocity().w;
        let (centre, v) =
            if trusted { track.ahead.ahead(tau, self.params.manoeuvre_s()) } else { (track.pos.x, Vector3::zeros()) };
        let velocity = TargetVelocity { v, w };
        let target = Isometry3::from_parts(Translation3::from(centre), exp_rotation(&(w * tau)) * track.orientation);
        let psi = Psi::from_isometry(&(camera.inverse() * target));
        Ok(Prediction { psi, velocity, trusted, base_time_us: track.time_us })
    }
}

/// `t1 − t0` in seconds (negative when `t1 < t0`).
fn seconds_between(t0_us: u64, t1_us: u64) -> f32 {
    if t1_us >= t0_us { (t1_us - t0_us) as f32 * 1e-6 } else { -((t0_us - t1_us) as f32 * 1e-6) }
}
