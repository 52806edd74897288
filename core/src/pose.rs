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

    /// The pose turned by the rotation `turn` (axis and angle in the reference frame) about
    /// the mean depth of the surface of a box of half edge lengths `half` that a camera at the
    /// origin sees: a point on the viewing ray through the position, `h_x·h_y·h_z / Σ_k c_k·h_i·h_j`
    /// in front of it (`c_k` the cosine between the ray and the box's axis `k`, `h_i`, `h_j` the
    /// other two half edges), which is each visible face's depth `h_k` weighted by the area it
    /// shows (half the volume over the silhouette's area). The position moves so that this
    /// point stays put: a face seen face-on keeps its place in the image as the box turns. The
    /// pose itself when the position is at the origin or not finite.
    pub fn turned_about_surface(&self, turn: &UnitQuaternion<f32>, half: &[f32; 3]) -> Psi {
        let t = self.translation();
        let range = t.norm();
        if !(range > 1e-6 && range.is_finite()) {
            return *self;
        }
        let ray = t / range;
        let u = self.rotation_unchecked().transpose() * ray;
        let [hx, hy, hz] = *half;
        let seen = u.x.abs() * hy * hz + u.y.abs() * hx * hz + u.z.abs() * hx * hy;
        let lever = if seen > 0.0 { hx * hy * hz / seen } else { 0.0 };
        let pivot = t - ray * lever;
        let moved = pivot + quat::to_rotation_matrix(turn) * (ray * lever);
        Psi::from_parts(&moved, &quat::compose(turn, &self.quaternion_unchecked()))
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

    /// Where the pose `psi` puts the block's point `p` (block frame).
    fn place(psi: &Psi, p: Vector3<f32>) -> Vector3<f32> {
        psi.rotation_unchecked() * p + psi.translation()
    }

    #[test]
    fn a_turn_about_the_surface_keeps_a_face_seen_face_on_in_place() {
        let half = [0.05, 0.075, 0.1];
        let psi = Psi::new([0.0, 0.0, 1.0], [0.0; 3]);
        let turn = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.2);
        let turned = psi.turned_about_surface(&turn, &half);
        // Face-on along the block's z axis: the face nearest the camera, 0.1 m in front.
        let near = Vector3::new(0.0, 0.0, -0.1);
        assert!((place(&turned, near) - place(&psi, near)).norm() < 1e-6);
        let q = turned.quaternion_unchecked();
        assert!(q.angle_to(&turn) < 1e-5, "the orientation is the turn composed on the left");
        // Turned about its centre instead, that face would have moved 0.1·sin(0.2) ≈ 20 mm.
        assert!((place(&Psi::from_parts(&psi.translation(), &q), near) - place(&psi, near)).norm() > 0.019);
    }

    #[test]
    fn the_turns_pivot_is_the_seen_surfaces_mean_depth() {
        let half = [0.05, 0.075, 0.1];
        // Seen at 45° between the block's x and z faces: both show the same area per unit of
        // their own (4·h_y·h_z and 4·h_x·h_y) at cosine 1/√2.
        let q = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), core::f32::consts::FRAC_PI_4);
        let psi = Psi::from_parts(&Vector3::new(0.0, 0.0, 0.8), &q);
        let turn = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), 0.1);
        let turned = psi.turned_about_surface(&turn, &half);
        let c = core::f32::consts::FRAC_1_SQRT_2;
        let (a_x, a_z) = (4.0 * 0.075 * 0.1 * c, 4.0 * 0.05 * 0.075 * c);
        let depth = (a_x * 0.05 * c + a_z * 0.1 * c) / (a_x + a_z);
        let pivot = Vector3::new(0.0, 0.0, 0.8 - depth);
        let expected = pivot + quat::to_rotation_matrix(&turn) * (psi.translation() - pivot);
        assert!((turned.translation() - expected).norm() < 1e-6, "{:?} {expected:?}", turned.translation());
        // No box, or a pose at the camera: the turn about the centre, and the pose itself.
        assert!((psi.turned_about_surface(&turn, &[0.0; 3]).translation() - psi.translation()).norm() < 1e-7);
        assert_eq!(
            Psi::new([0.0; 3], [0.1, 0.0, 0.0]).turned_about_surface(&turn, &half),
            Psi::new([0.0; 3], [0.1, 0.0, 0.0])
        );
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
