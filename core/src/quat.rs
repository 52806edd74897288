//! Unit-quaternion orientation math (paper §2, eq. 1–12).
//!
//! A unit quaternion `Q = {η, ε}` has scalar part `η` and vector part `ε`, with
//! `η² + εᵀε = 1` (eq. 3). The storage type is nalgebra's [`UnitQuaternion`] (`w` = η,
//! `i, j, k` = ε); the paper's formulas are written out here so that each one is explicit,
//! tested on its own, and computed through [`crate::math`] (libm) only.
//!
//! `Q` and `−Q` describe the same rotation. Where a single representative is needed (the
//! 6-parameter pose of eq. 13 stores only ε), the one with `η ≥ 0` is taken; see
//! [`canonical`].

use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

use crate::math;

error_enum! {
    /// Why a quaternion could not be built.
    pub enum QuatError {
        /// An input held NaN or infinity.
        NonFinite => "input is not finite",
        /// The rotation axis had (near) zero length.
        ZeroAxis => "rotation axis has zero length",
        /// The matrix is not a rotation (not orthonormal within tolerance, or `det < 0`).
        NotRotation => "matrix is not a proper rotation",
    }
}

/// Tolerance on `‖RᵀR − I‖∞` and `|det R − 1|` accepted by [`from_rotation_matrix`].
pub const ROTATION_TOLERANCE: f32 = 1e-3;

/// The skew-symmetric cross-product matrix `S(v)` with `S(v)·w = v × w` (eq. 17).
pub fn skew(v: &Vector3<f32>) -> Matrix3<f32> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

/// Builds `{η, ε}` from its parts, normalised with libm's `sqrt`.
pub(crate) fn normalized(eta: f32, eps: Vector3<f32>) -> UnitQuaternion<f32> {
    let n = math::sqrt(eta * eta + eps.dot(&eps));
    UnitQuaternion::new_unchecked(Quaternion::new(eta / n, eps.x / n, eps.y / n, eps.z / n))
}

/// Rotation by `angle_rad` about `axis` (eq. 2): `η = cos(θ/2)`, `ε = sin(θ/2)·k`.
///
/// The axis need not be unit length; it is normalised first.
///
/// # Errors
/// [`QuatError::NonFinite`] for NaN/inf input, [`QuatError::ZeroAxis`] if `‖axis‖ < 1e-12`.
///
/// # Examples
/// ```
/// use evorec_core::quat;
/// use nalgebra::Vector3;
/// let q = quat::from_angle_axis(core::f32::consts::FRAC_PI_2, &Vector3::z()).unwrap();
/// assert!((q.w - core::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6);
/// assert!((q.k - core::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6);
/// assert!(quat::from_angle_axis(1.0, &Vector3::zeros()).is_err());
/// ```
pub fn from_angle_axis(angle_rad: f32, axis: &Vector3<f32>) -> Result<UnitQuaternion<f32>, QuatError> {
    if !angle_rad.is_finite() || !axis.iter().all(|c| c.is_finite()) {
        return Err(QuatError::NonFinite);
    }
    let n2 = axis.dot(axis);
    if n2 < 1e-24 {
        return Err(QuatError::ZeroAxis);
    }
    let k = axis / math::sqrt(n2);
    let (s, c) = math::sin_cos(0.5 * angle_rad);
    Ok(normalized(c, k * s))
}

/// The rotation matrix of a unit quaternion (eq. 4):
/// `R = (η² − εᵀε) I + 2 ε εᵀ + 2 η S(ε)`.
pub fn to_rotation_matrix(q: &UnitQuaternion<f32>) -> Matrix3<f32> {
    let eta = q.w;
    let e = q.imag();
    Matrix3::identity() * (eta * eta - e.dot(&e)) + (e * e.transpose()) * 2.0 + skew(&e) * (2.0 * eta)
}

/// The quaternion of a rotation matrix, robust for every rotation, with `η ≥ 0`.
///
/// Eq. 5–6 divide by `4η` and lose all precision as `1 + tr R → 0` (rotations near 180°).
/// This uses Shepperd's method: of `η² ∝ 1 + tr R` and `ε_i² ∝ 1 + 2R_ii − tr R` it takes the
/// largest (at least ¼), computes that component with a square root, and the other three from
/// the off-diagonal sums and differences, which are then well conditioned. The result is
/// normalised and mapped to `η ≥ 0` ([`canonical`]).
///
/// # Errors
/// [`QuatError::NonFinite`], or [`QuatError::NotRotation`] if `R` is not orthonormal with
/// `det R = +1` within [`ROTATION_TOLERANCE`].
pub fn from_rotation_matrix(r: &Matrix3<f32>) -> Result<UnitQuaternion<f32>, QuatError> {
    if !r.iter().all(|c| c.is_finite()) {
        return Err(QuatError::NonFinite);
    }
    let gram = r.transpose() * r - Matrix3::identity();
    if gram.iter().any(|c| c.abs() > ROTATION_TOLERANCE) || (r.determinant() - 1.0).abs() > ROTATION_TOLERANCE {
        return Err(QuatError::NotRotation);
    }
    let (m00, m01, m02) = (r.m11, r.m12, r.m13);
    let (m10, m11, m12) = (r.m21, r.m22, r.m23);
    let (m20, m21, m22) = (r.m31, r.m32, r.m33);
    let tr = m00 + m11 + m22;
    let q = if tr >= m00 && tr >= m11 && tr >= m22 {
        let s = 2.0 * math::sqrt(1.0 + tr); // s = 4η
        Quaternion::new(0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s)
    } else if m00 >= m11 && m00 >= m22 {
        let s = 2.0 * math::sqrt(1.0 + m00 - m11 - m22); // s = 4ε₁
        Quaternion::new((m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s)
    } else if m11 >= m22 {
        let s = 2.0 * math::sqrt(1.0 + m11 - m00 - m22); // s = 4ε₂
        Quaternion::new((m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s)
    } else {
        let s = 2.0 * math::sqrt(1.0 + m22 - m00 - m11); // s = 4ε₃
        Quaternion::new((m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s)
    };
    Ok(canonical(&normalized(q.w, q.imag())))
}

/// Composition `Q₂ = Q₁ * Q₂₁` (eq. 10–12), the quaternion of `R₂ = R₁ R₂₁`:
/// `η₂ = η₁η₂₁ − ε₁ᵀε₂₁`, `ε₂ = η₁ε₂₁ + η₂₁ε₁ + S(ε₁)ε₂₁`. The result is renormalised.
pub fn compose(q1: &UnitQuaternion<f32>, q21: &UnitQuaternion<f32>) -> UnitQuaternion<f32> {
    let (e1, e21) = (q1.imag(), q21.imag());
    let eta = q1.w * q21.w - e1.dot(&e21);
    let eps = e21 * q1.w + e1 * q21.w + e1.cross(&e21);
    normalized(eta, eps)
}

/// The representative of `±Q` with `η ≥ 0`.
///
/// When `η = 0` exactly both signs have `η = 0`; then the one whose first non-zero component
/// of `ε` is positive is returned, so the map is a function of the rotation alone.
pub fn canonical(q: &UnitQuaternion<f32>) -> UnitQuaternion<f32> {
    let flip = if q.w != 0.0 {
        q.w < 0.0
    } else if q.i != 0.0 {
        q.i < 0.0
    } else if q.j != 0.0 {
        q.j < 0.0
    } else {
        q.k < 0.0
    };
    if flip { UnitQuaternion::new_unchecked(-q.into_inner()) } else { *q }
}

/// Time derivative of `{η, ε}` under angular velocity `ω` (propagation rule, eq. 7–8):
/// `η̇ = −½ εᵀω`, `ε̇ = ½ (ηI − S(ε)) ω`.
///
/// `ω` is expressed in the reference frame of the orientation (for `^CR Q_M`, in `Σ_CR`), i.e.
/// `Ṙ = S(ω) R`.
pub fn propagation(q: &UnitQuaternion<f32>, omega: &Vector3<f32>) -> (f32, Vector3<f32>) {
    let e = q.imag();
    let eta_dot = -0.5 * e.dot(omega);
    let eps_dot = (omega * q.w - skew(&e) * omega) * 0.5;
    (eta_dot, eps_dot)
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f32::consts::{FRAC_1_SQRT_2, FRAC_PI_2, PI};
    use proptest::prelude::*;

    fn assert_mat_close(a: &Matrix3<f32>, b: &Matrix3<f32>, tol: f32) {
        for (x, y) in a.iter().zip(b.iter()) {
            assert!((x - y).abs() <= tol, "{a} vs {b}");
        }
    }

    fn same_rotation(a: &UnitQuaternion<f32>, b: &UnitQuaternion<f32>, tol: f32) -> bool {
        let d = a.coords.dot(&b.coords).abs();
        (1.0 - d).abs() <= tol
    }

    #[test]
    fn angle_axis_independent_values() {
        // 90° about z: R = [[0,-1,0],[1,0,0],[0,0,1]].
        let q = from_angle_axis(FRAC_PI_2, &Vector3::new(0.0, 0.0, 2.0)).unwrap();
        assert!((q.w - FRAC_1_SQRT_2).abs() < 1e-6 && (q.k - FRAC_1_SQRT_2).abs() < 1e-6);
        let expected = Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
        assert_mat_close(&to_rotation_matrix(&q), &expected, 1e-6);
        // 120° about (1,1,1)/√3 permutes the axes: x→y, y→z, z→x; quaternion {1/2, 1/2, 1/2, 1/2}.
        let q = from_angle_axis(2.0 * PI / 3.0, &Vector3::new(1.0, 1.0, 1.0)).unwrap();
        for c in [q.w, q.i, q.j, q.k] {
            assert!((c - 0.5).abs() < 1e-6);
        }
        let expected = Matrix3::new(0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0);
        assert_mat_close(&to_rotation_matrix(&q), &expected, 1e-6);
    }

    #[test]
    fn angle_axis_rejects_bad_input() {
        assert_eq!(from_angle_axis(1.0, &Vector3::zeros()), Err(QuatError::ZeroAxis));
        assert_eq!(from_angle_axis(f32::NAN, &Vector3::x()), Err(QuatError::NonFinite));
        assert_eq!(from_angle_axis(1.0, &Vector3::new(f32::INFINITY, 0.0, 0.0)), Err(QuatError::NonFinite));
    }

    #[test]
    fn pa10_reference_quaternions_from_matrices() {
        // Flange rotations of the PA-10 and their quaternions ([x, y, z, w], w ≥ 0), computed by
        // a third-party toolbox (the values shared with the kinematics tests).
        for case in &crate::kinematics::reference::CASES {
            let q = from_rotation_matrix(&Matrix3::from_row_slice(&case.r)).unwrap();
            let xyzw = case.quat_xyzw;
            assert!((q.i - xyzw[0]).abs() < 1e-5, "{q:?}");
            assert!((q.j - xyzw[1]).abs() < 1e-5);
            assert!((q.k - xyzw[2]).abs() < 1e-5);
            assert!((q.w - xyzw[3]).abs() < 1e-5);
        }
    }

    #[test]
    fn matrix_to_quaternion_near_180_degrees() {
        // 1 + tr R = 0 exactly: eq. 5–6 would divide by zero.
        for axis in [Vector3::x(), Vector3::y(), Vector3::z(), Vector3::new(1.0, -2.0, 0.5)] {
            let q = from_angle_axis(PI, &axis).unwrap();
            let back = from_rotation_matrix(&to_rotation_matrix(&q)).unwrap();
            assert!(same_rotation(&q, &back, 1e-6), "{q:?} {back:?}");
            assert!(back.w >= 0.0);
        }
    }

    #[test]
    fn matrix_to_quaternion_rejects_non_rotations() {
        let reflect = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
        assert_eq!(from_rotation_matrix(&reflect), Err(QuatError::NotRotation));
        assert_eq!(from_rotation_matrix(&(Matrix3::identity() * 2.0)), Err(QuatError::NotRotation));
        let mut nan = Matrix3::identity();
        nan.m12 = f32::NAN;
        assert_eq!(from_rotation_matrix(&nan), Err(QuatError::NonFinite));
    }

    #[test]
    fn composition_independent_value() {
        // 90° about x, then 90° about the new y: R = Rx(90) Ry(90) = [[0,0,1],[1,0,0],[0,1,0]],
        // whose quaternion is {1/2, 1/2, 1/2, 1/2}.
        let qx = from_angle_axis(FRAC_PI_2, &Vector3::x()).unwrap();
        let qy = from_angle_axis(FRAC_PI_2, &Vector3::y()).unwrap();
        let q = compose(&qx, &qy);
        for c in [q.w, q.i, q.j, q.k] {
            assert!((c - 0.5).abs() < 1e-6, "{q:?}");
        }
        assert_mat_close(&to_rotation_matrix(&q), &(to_rotation_matrix(&qx) * to_rotation_matrix(&qy)), 1e-6);
    }

    #[test]
    fn canonical_tie_break_at_eta_zero() {
        let q = UnitQuaternion::new_unchecked(Quaternion::new(0.0, 0.0, -1.0, 0.0));
        let c = canonical(&q);
        assert_eq!((c.w, c.i, c.j, c.k), (0.0, 0.0, 1.0, 0.0));
        let p = UnitQuaternion::new_unchecked(Quaternion::new(-0.6, 0.8, 0.0, 0.0));
        let c = canonical(&p);
        assert!((c.w - 0.6).abs() < 1e-7 && (c.i + 0.8).abs() < 1e-7);
    }

    #[test]
    fn propagation_matches_finite_difference() {
        let q = from_angle_axis(0.7, &Vector3::new(0.3, -1.0, 0.4)).unwrap();
        let w = Vector3::new(0.2, -0.5, 0.9);
        let (eta_dot, eps_dot) = propagation(&q, &w);
        let h = 1e-3;
        // R(t+h) = exp(S(w)h) R(t): the quaternion of the increment composed on the left.
        let dq = from_angle_axis(w.norm() * h, &w).unwrap();
        let q2 = compose(&dq, &q);
        assert!(((q2.w - q.w) / h - eta_dot).abs() < 2e-3);
        assert!(((q2.imag() - q.imag()) / h - eps_dot).norm() < 2e-3);
    }

    prop_compose! {
        fn unit_quat()(w in -1.0f32..1.0, x in -1.0f32..1.0, y in -1.0f32..1.0, z in -1.0f32..1.0)
            -> UnitQuaternion<f32> {
            let n = (w * w + x * x + y * y + z * z).max(1e-3);
            let s = 1.0 / math::sqrt(n);
            normalized(w * s + if n < 1e-3 { 1.0 } else { 0.0 }, Vector3::new(x * s, y * s, z * s))
        }
    }

    proptest! {
        #[test]
        fn matrix_quaternion_round_trip(q in unit_quat()) {
            let back = from_rotation_matrix(&to_rotation_matrix(&q)).unwrap();
            prop_assert!(same_rotation(&q, &back, 2e-6), "{:?} {:?}", q, back);
            prop_assert!(back.w >= 0.0);
            let r = to_rotation_matrix(&q);
            let r2 = to_rotation_matrix(&back);
            for (a, b) in r.iter().zip(r2.iter()) { prop_assert!((a - b).abs() < 1e-5); }
        }

        #[test]
        fn matrix_of_quaternion_equals_nalgebra(q in unit_quat()) {
            let ours = to_rotation_matrix(&q);
            let theirs = q.to_rotation_matrix().into_inner();
            for (a, b) in ours.iter().zip(theirs.iter()) { prop_assert!((a - b).abs() < 1e-5); }
        }

        #[test]
        fn composition_is_associative_and_matches_matrices(a in unit_quat(), b in unit_quat(), c in unit_quat()) {
            let left = compose(&compose(&a, &b), &c);
            let right = compose(&a, &compose(&b, &c));
            prop_assert!(same_rotation(&left, &right, 1e-5));
            let rm = to_rotation_matrix(&a) * to_rotation_matrix(&b);
            let rq = to_rotation_matrix(&compose(&a, &b));
            for (x, y) in rm.iter().zip(rq.iter()) { prop_assert!((x - y).abs() < 1e-5); }
        }

        #[test]
        fn canonical_has_nonnegative_eta_and_same_rotation(q in unit_quat()) {
            let c = canonical(&q);
            prop_assert!(c.w >= 0.0);
            prop_assert!(same_rotation(&q, &c, 1e-6));
            let neg = UnitQuaternion::new_unchecked(-q.into_inner());
            prop_assert_eq!(canonical(&neg).coords, c.coords);
        }
    }
}
