//! The 6-parameter pose `ψ = [t; ε]` (paper eq. 13) and its conversions.
//!
//! `t` is the position of the target frame `Σ_M` in the reference frame (metres) and `ε` the
//! vector part of the target's unit quaternion; the scalar part is implied,
//! `η = +√(1 − |ε|²)`, so a `ψ` always stands for the `η ≥ 0` representative of `±Q`
//! ([`crate::quat::canonical`]). Every `ψ` with `|ε| ≤ 1` is a valid pose.

use nalgebra::{Isometry3, Matrix3, Quaternion, Translation3, UnitQuaternion, Vector3};

use crate::{math, quat};

error_enum! {
    /// Why a `ψ` is not a pose.
    pub enum PoseError {
        /// A component is NaN or infinite.
        NonFinite => "pose has a non-finite component",
        /// `|ε| > 1` (beyond [`EPS_NORM_TOLERANCE`]): no real `η` exists.
        EpsOutOfBall => "quaternion vector part has norm > 1",
    }
}

/// `|ε|²` may exceed 1 by this much (rounding) and still be accepted (then `η = 0`).
pub const EPS_NORM_TOLERANCE: f32 = 1e-5;

/// Pose `ψ = [t_x, t_y, t_z, ε₁, ε₂, ε₃]`: metres and quaternion vector part.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Psi(pub [f32; 6]);

impl Psi {
    /// The identity pose at the origin.
    pub const IDENTITY: Psi = Psi([0.0; 6]);

    /// A pose from its position (m) and quaternion vector part.
    pub const fn new(t: [f32; 3], eps: [f32; 3]) -> Self {
        Psi([t[0], t[1], t[2], eps[0], eps[1], eps[2]])
    }

    /// Position `t` (metres).
    pub fn translation(&self) -> Vector3<f32> {
        let [x, y, z, ..] = self.0;
        Vector3::new(x, y, z)
    }

    /// The pose moved along the right camera's viewing ray through its position: the
    /// translation scaled by `factor` (the depth `t_z` becomes `factor · t_z`, the image of the
    /// centre in the right camera stays put), the orientation kept.
    pub fn scaled_along_ray(&self, factor: f32) -> Psi {
        let mut p = *self;
        for x in p.0.iter_mut().take(3) {
            *x *= factor;
        }
        p
    }

    /// Quaternion vector part `ε`.
    pub fn eps(&self) -> Vector3<f32> {
        let [.., a, b, c] = self.0;
        Vector3::new(a, b, c)
    }

    /// Scalar part `η = √(1 − |ε|²)`, 0 where `|ε| ≥ 1`.
    pub fn eta(&self) -> f32 {
        let e = self.eps();
        math::sqrt(math::clamp(1.0 - e.dot(&e), 0.0, 1.0))
    }

    /// Checks that `ψ` is finite and `|ε|² ≤ 1 + EPS_NORM_TOLERANCE`.
    ///
    /// # Errors
    /// [`PoseError::NonFinite`] or [`PoseError::EpsOutOfBall`].
    pub fn validate(&self) -> Result<(), PoseError> {
        if !self.0.iter().all(|c| c.is_finite()) {
            return Err(PoseError::NonFinite);
        }
        let e = self.eps();
        if e.dot(&e) > 1.0 + EPS_NORM_TOLERANCE {
            return Err(PoseError::EpsOutOfBall);
        }
        Ok(())
    }

    /// The unit quaternion `{η, ε}` (η ≥ 0), normalised.
    ///
    /// # Errors
    /// As [`Psi::validate`].
    pub fn try_quaternion(&self) -> Result<UnitQuaternion<f32>, PoseError> {
        self.validate()?;
        Ok(self.quaternion_unchecked())
    }

    /// The unit quaternion without validation: the caller promises `ψ` is finite with
    /// `|ε| ≤ 1` (as every GA individual is). Never panics; garbage in, garbage out.
    pub fn quaternion_unchecked(&self) -> UnitQuaternion<f32> {
        let e = self.eps();
        let eta = self.eta();
        let n = math::sqrt(eta * eta + e.dot(&e));
        let n = if n > 0.0 { n } else { 1.0 };
        UnitQuaternion::new_unchecked(Quaternion::new(eta / n, e.x / n, e.y / n, e.z / n))
    }

    /// Rotation matrix of the pose (eq. 4), without validation (see
    /// [`Psi::quaternion_unchecked`]).
    pub fn rotation_unchecked(&self) -> Matrix3<f32> {
        quat::to_rotation_matrix(&self.quaternion_unchecked())
    }

    /// The homogeneous transform of the pose.
    ///
    /// # Errors
    /// As [`Psi::validate`].
    pub fn try_to_isometry(&self) -> Result<Isometry3<f32>, PoseError> {
        let q = self.try_quaternion()?;
        Ok(Isometry3::from_parts(Translation3::from(self.translation()), q))
    }

    /// `ψ` of a transform, choosing the `η ≥ 0` representative (eq. 13).
    pub fn from_isometry(iso: &Isometry3<f32>) -> Self {
        Self::from_parts(&iso.translation.vector, &iso.rotation)
    }

    /// `ψ` of a position and an orientation, choosing the `η ≥ 0` representative.
    pub fn from_parts(t: &Vector3<f32>, q: &UnitQuaternion<f32>) -> Self {
        let c = quat::canonical(q);
        Psi([t.x, t.y, t.z, c.i, c.j, c.k])
    }

    /// Scales `ε` back onto the unit sphere when `|ε| > 1` (so `η = 0`), leaving it unchanged
    /// otherwise. Non-finite components are replaced by 0. Used after the GA's arithmetic.
    pub fn project_to_ball(&mut self) {
        for c in self.0.iter_mut() {
            if !c.is_finite() {
                *c = 0.0;
            }
        }
        let e = self.eps();
        let n2 = e.dot(&e);
        if n2 > 1.0 {
            let s = 1.0 / math::sqrt(n2);
            let [.., a, b, c] = &mut self.0;
            *a *= s;
            *b *= s;
            *c *= s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn validation() {
        assert_eq!(Psi::new([0.0; 3], [0.6, 0.8, 0.1]).validate(), Err(PoseError::EpsOutOfBall));
        assert_eq!(Psi::new([f32::NAN, 0.0, 0.0], [0.0; 3]).validate(), Err(PoseError::NonFinite));
        assert!(Psi::new([1.0, 2.0, 3.0], [0.6, 0.8, 0.0]).validate().is_ok());
        assert_eq!(Psi::new([0.0; 3], [0.6, 0.8, 0.0]).eta(), 0.0);
    }

    #[test]
    fn negative_eta_maps_to_upper_hemisphere() {
        // {η, ε} = {-0.8, 0.6, 0, 0} is the same rotation as {0.8, -0.6, 0, 0}.
        let q = UnitQuaternion::new_unchecked(Quaternion::new(-0.8, 0.6, 0.0, 0.0));
        let psi = Psi::from_parts(&Vector3::zeros(), &q);
        assert!((psi.0[3] + 0.6).abs() < 1e-7);
        assert!((psi.eta() - 0.8).abs() < 1e-6);
    }

    #[test]
    fn project_to_ball_scales_and_cleans() {
        let mut p = Psi::new([f32::NAN, 1.0, 2.0], [3.0, 4.0, 0.0]);
        p.project_to_ball();
        assert_eq!(p.0[0], 0.0);
        assert!((p.0[3] - 0.6).abs() < 1e-6 && (p.0[4] - 0.8).abs() < 1e-6);
        assert!(p.validate().is_ok());
    }

    proptest! {
        #[test]
        fn psi_quaternion_round_trip(
            t in proptest::array::uniform3(-2.0f32..2.0),
            e in proptest::array::uniform3(-0.577f32..0.577),
        ) {
            let psi = Psi::new(t, e);
            let iso = psi.try_to_isometry().unwrap();
            let back = Psi::from_isometry(&iso);
            for (a, b) in psi.0.iter().zip(back.0.iter()) { prop_assert!((a - b).abs() < 1e-6); }
            prop_assert!(iso.rotation.w >= 0.0);
        }

        #[test]
        fn any_quaternion_gives_eta_nonnegative_psi(
            w in -1.0f32..1.0, x in -1.0f32..1.0, y in -1.0f32..1.0, z in -1.0f32..1.0,
        ) {
            let n = math::sqrt(w * w + x * x + y * y + z * z);
            prop_assume!(n > 1e-2);
            let q = UnitQuaternion::new_unchecked(Quaternion::new(w / n, x / n, y / n, z / n));
            let psi = Psi::from_parts(&Vector3::zeros(), &q);
            let q2 = psi.try_quaternion().unwrap();
            prop_assert!(q2.w >= 0.0);
            prop_assert!((q2.coords.dot(&q.coords).abs() - 1.0).abs() < 1e-5);
        }
    }
}
