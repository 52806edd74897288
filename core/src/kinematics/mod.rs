//! Serial-chain kinematics (paper §3, eq. 20–21): forward kinematics and the geometric
//! Jacobian of any serial arm of `DOF` revolute or prismatic joints.
//!
//! Joint `i` is a fixed rigid transform from the previous joint's moving frame (or the base)
//! to the joint's own frame, followed by the joint's motion: a rotation about (revolute) or a
//! translation along (prismatic) the `z` axis of that frame. A fixed tip transform leads from
//! the last joint's moving frame to the flange, so
//!
//! ```text
//! ^W T_H(q) = O_1 · M_1(q_1) · O_2 · M_2(q_2) ⋯ O_DOF · M_DOF(q_DOF) · O_tip
//! ```
//!
//! with `M_i = Rz(q_i)` or `Tz(q_i)`. Every fixed transform is a [`Frame`] of plain arrays, so a
//! [`Chain`] is `const`-constructible (firmware holds its arm as a `const`). A joint axis in any
//! direction (as URDF gives it) is turned into this `z`-axis form once, by [`Chain::new_checked`],
//! which also validates data from outside (finite, rigid, unit axis, ordered limits); the
//! forward kinematics then costs one `sin_cos` per revolute joint. Denavit–Hartenberg tables are
//! one way to build a chain ([`dh`], [`Chain::from_dh`]); [`PA10`] is the Mitsubishi PA-10.
//!
//! Forward kinematics and Jacobian never panic, whatever `q` (NaN in gives NaN out).

use nalgebra::{Isometry3, Matrix3, SMatrix, Translation3, UnitQuaternion, Vector3};

use crate::{math, quat};

pub mod dh;
#[cfg(test)]
pub(crate) mod reference;
#[cfg(test)]
mod tests;

pub use dh::{DhLink, PA10, PA10_DH};

/// Joint positions (rad) and velocities (rad/s) sampled at `time_us`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointSample<const DOF: usize> {
    /// Joint positions.
    pub q: [f32; DOF],
    /// Joint velocities.
    pub qd: [f32; DOF],
    /// Sample time (µs, the board's clock).
    pub time_us: u64,
}

/// Largest deviation of `RᵀR` from `I` (per entry) accepted for a rigid transform.
pub const RIGID_TOLERANCE: f32 = 1e-4;

/// Largest deviation of a joint axis' length from 1 that [`Chain::new_checked`] normalises away.
pub const AXIS_TOLERANCE: f32 = 1e-3;

/// A rigid transform as plain arrays: `x ↦ rotation · x + translation`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Rotation matrix, row-major (`rotation[row][col]`).
    pub rotation: [[f32; 3]; 3],
    /// Translation (m).
    pub translation: [f32; 3],
}

impl Frame {
    /// The identity transform.
    pub const IDENTITY: Frame = Frame::translation(0.0, 0.0, 0.0);

    /// A pure translation.
    pub const fn translation(x: f32, y: f32, z: f32) -> Frame {
        Frame { rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], translation: [x, y, z] }
    }

    /// The rotation as a matrix.
    pub fn rotation_matrix(&self) -> Matrix3<f32> {
        let r = &self.rotation;
        Matrix3::new(r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2])
    }

    /// The translation as a vector.
    pub fn translation_vector(&self) -> Vector3<f32> {
        Vector3::from(self.translation)
    }

    /// A frame from a rotation matrix and a translation (taken as they are).
    pub fn from_parts(r: &Matrix3<f32>, t: &Vector3<f32>) -> Frame {
        Frame {
            rotation: [
                [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
                [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
                [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
            ],
            translation: [t.x, t.y, t.z],
        }
    }

    /// The frame of an isometry.
    pub fn from_isometry(iso: &Isometry3<f32>) -> Frame {
        Frame::from_parts(&quat::to_rotation_matrix(&iso.rotation), &iso.translation.vector)
    }

    /// The isometry of this frame (see [`isometry`]).
    pub fn to_isometry(&self) -> Isometry3<f32> {
        isometry(&self.rotation_matrix(), &self.translation_vector())
    }

    /// `self · other`.
    pub fn compose(&self, other: &Frame) -> Frame {
        let r = self.rotation_matrix();
        Frame::from_parts(&(r * other.rotation_matrix()), &(r * other.translation_vector() + self.translation_vector()))
    }

    /// Whether every number is finite.
    pub fn is_finite(&self) -> bool {
        self.rotation.iter().flatten().chain(self.translation.iter()).all(|v| v.is_finite())
    }

    /// Whether the rotation is a proper rotation (`RᵀR = I` within [`RIGID_TOLERANCE`],
    /// `det R > 0`) and every number is finite.
    pub fn is_rigid(&self) -> bool {
        let r = self.rotation_matrix();
        let off = (r.transpose() * r - Matrix3::identity()).abs().max();
        self.is_finite() && off <= RIGID_TOLERANCE && r.determinant() > 0.0
    }
}

/// How a joint moves, always along or about the `z` axis of its frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum JointKind {
    /// Rotation about `z` by `q` (rad).
    Revolute,
    /// Translation along `z` by `q` (m).
    Prismatic,
}

/// One joint of a [`Chain`]: fixed transform from the parent, then motion about/along `z`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Joint {
    /// Fixed transform from the previous joint's moving frame (or the base) to this joint's
    /// frame, whose `z` axis is the joint axis.
    pub origin: Frame,
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Lower limit (rad or m; `−∞` for none).
    pub q_min: f32,
    /// Upper limit (rad or m; `+∞` for none).
    pub q_max: f32,
}

impl Joint {
    /// A revolute joint about `z` of `origin`.
    pub const fn revolute(origin: Frame, q_min: f32, q_max: f32) -> Joint {
        Joint { origin, kind: JointKind::Revolute, q_min, q_max }
    }
}

/// A joint described as URDF does: fixed origin, then motion about/along `axis` (a unit vector
/// in the joint frame). Input of [`Chain::new_checked`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct JointSpec {
    /// Fixed transform from the previous joint's moving frame (or the base).
    pub origin: Frame,
    /// Joint axis in the joint frame (unit length within [`AXIS_TOLERANCE`]).
    pub axis: [f32; 3],
    /// Revolute or prismatic.
    pub kind: JointKind,
    /// Lower limit (`−∞` for none).
    pub q_min: f32,
    /// Upper limit (`+∞` for none).
    pub q_max: f32,
}

/// Which part of a chain an error is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChainPart {
    /// Joint `i` (0-based, base to flange).
    Joint(usize),
    /// The fixed tip transform to the flange.
    Tip,
}

/// Why a chain was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChainError {
    /// A NaN or infinite number in a transform or axis.
    NotFinite(ChainPart),
    /// A rotation that is not a proper rotation (not orthonormal, or a reflection).
    NotRigid(ChainPart),
    /// A joint axis that is not a unit vector (zero, or length far from 1).
    AxisNotUnit(usize),
    /// A limit that is NaN, or a lower limit above the upper one.
    LimitsNotOrdered(usize),
}

impl core::fmt::Display for ChainPart {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ChainPart::Joint(i) => write!(f, "joint {}", i + 1),
            ChainPart::Tip => f.write_str("tip transform"),
        }
    }
}

impl core::fmt::Display for ChainError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ChainError::NotFinite(p) => write!(f, "{p}: a number is not finite"),
            ChainError::NotRigid(p) => write!(f, "{p}: the rotation is not orthonormal with determinant +1"),
            ChainError::AxisNotUnit(i) => write!(f, "joint {}: the axis is not a unit vector", i + 1),
            ChainError::LimitsNotOrdered(i) => write!(f, "joint {}: lower limit is not below the upper limit", i + 1),
        }
    }
}

impl core::error::Error for ChainError {}

/// A chain of `DOF` joints from the base to the flange.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chain<const DOF: usize> {
    /// The joints, base to flange.
    pub joints: [Joint; DOF],
    /// Fixed transform from the last joint's moving frame to the flange.
    pub tip: Frame,
}

/// The rotation taking `z` onto the unit vector `a` (exact for `a = ±z`).
fn rotation_z_to(a: &Vector3<f32>) -> Matrix3<f32> {
    // Rodrigues about z × a, written for b = ±a with b_z ≥ 0 (stable), then flipped by Rx(π).
    let flip = a.z < 0.0;
    let b = if flip { -a } else { *a };
    let k = 1.0 / (1.0 + b.z);
    let r = Matrix3::new(
        1.0 - b.x * b.x * k,
        -b.x * b.y * k,
        b.x,
        -b.x * b.y * k,
        1.0 - b.y * b.y * k,
        b.y,
        -b.x,
        -b.y,
        b.z,
    );
    if flip { r * Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0)) } else { r }
}

impl<const DOF: usize> Chain<DOF> {
    /// A chain from joints described with arbitrary axes (as URDF does), validated: every
    /// number finite, every rotation rigid, every axis of unit length within
    /// [`AXIS_TOLERANCE`] (then normalised), limits ordered (infinite limits allowed).
    /// Each axis is turned into the `z` axis of its joint frame by folding a constant
    /// rotation into the joint's origin and its inverse into the next origin (or the tip),
    /// which leaves forward kinematics and Jacobian unchanged.
    ///
    /// # Errors
    /// [`ChainError`] naming the first offending joint (or the tip).
    pub fn new_checked(joints: &[JointSpec; DOF], tip: &Frame) -> Result<Self, ChainError> {
        let mut out = [Joint::revolute(Frame::IDENTITY, 0.0, 0.0); DOF];
        let mut carry = Matrix3::<f32>::identity(); // Aᵀ of the previous joint
        for (i, (spec, joint)) in joints.iter().zip(out.iter_mut()).enumerate() {
            check_frame(&spec.origin, ChainPart::Joint(i))?;
            let axis = Vector3::from(spec.axis);
            if !axis.iter().all(|v| v.is_finite()) {
                return Err(ChainError::NotFinite(ChainPart::Joint(i)));
            }
            let norm = math::sqrt(axis.norm_squared());
            if (norm - 1.0).abs() > AXIS_TOLERANCE {
                return Err(ChainError::AxisNotUnit(i));
            }
            if !limits_ordered(spec.q_min, spec.q_max) {
                return Err(ChainError::LimitsNotOrdered(i));
            }
            let a = rotation_z_to(&(axis / norm));
            let r = carry * spec.origin.rotation_matrix() * a;
            let t = carry * spec.origin.translation_vector();
            *joint = Joint { origin: Frame::from_parts(&r, &t), kind: spec.kind, q_min: spec.q_min, q_max: spec.q_max };
            carry = a.transpose();
        }
        check_frame(tip, ChainPart::Tip)?;
        let tip = Frame::from_parts(&(carry * tip.rotation_matrix()), &(carry * tip.translation_vector()));
        let chain = Chain { joints: out, tip };
        chain.validate()?;
        Ok(chain)
    }

    /// Checks a chain built directly (e.g. a `const`): finite rigid transforms, ordered limits.
    ///
    /// # Errors
    /// [`ChainError`] naming the first offending joint (or the tip).
    pub fn validate(&self) -> Result<(), ChainError> {
        for (i, j) in self.joints.iter().enumerate() {
            check_frame(&j.origin, ChainPart::Joint(i))?;
            if !limits_ordered(j.q_min, j.q_max) {
                return Err(ChainError::LimitsNotOrdered(i));
            }
        }
        check_frame(&self.tip, ChainPart::Tip)
    }

    /// The frames of all joints and the flange at one configuration, by matrix products
    /// (no quaternion round trip). One `sin_cos` per revolute joint.
    pub fn frames(&self, q: &[f32; DOF]) -> Frames<DOF> {
        let mut rots = [Matrix3::identity(); DOF];
        let mut origins = [Vector3::zeros(); DOF];
        let mut r = Matrix3::identity();
        let mut p = Vector3::zeros();
        for ((joint, qi), (ri, pi)) in self.joints.iter().zip(q.iter()).zip(rots.iter_mut().zip(origins.iter_mut())) {
            p += r * joint.origin.translation_vector();
            r *= joint.origin.rotation_matrix();
            *ri = r;
            *pi = p;
            match joint.kind {
                JointKind::Revolute => r = rotate_about_z(&r, *qi),
                JointKind::Prismatic => p += r.column(2) * *qi,
            }
        }
        p += r * self.tip.translation_vector();
        r *= self.tip.rotation_matrix();
        Frames { rotations: rots, origins, flange_rotation: r, flange_origin: p }
    }

    /// Flange rotation and position in the base frame.
    pub fn forward_rp(&self, q: &[f32; DOF]) -> (Matrix3<f32>, Vector3<f32>) {
        let f = self.frames(q);
        (f.flange_rotation, f.flange_origin)
    }

    /// Flange pose `^W T_H(q)`.
    pub fn forward(&self, q: &[f32; DOF]) -> Isometry3<f32> {
        let (r, p) = self.forward_rp(q);
        isometry(&r, &p)
    }

    /// Geometric Jacobian `J = [J_p; J_o]` (rows `v_x v_y v_z ω_x ω_y ω_z`, base frame) of a
    /// tool frame rigidly attached to the flange at `flange_to_tool` (`^H T_tool`), with the
    /// tool origin as reference point. Returns the tool rotation and origin too.
    ///
    /// Column `i` with joint axis `z_i` through `p_i`: revolute
    /// `[z_i × (p_tool − p_i); z_i]`, prismatic `[z_i; 0]`.
    pub fn jacobian_at(
        &self,
        q: &[f32; DOF],
        flange_to_tool: &Isometry3<f32>,
    ) -> (SMatrix<f32, 6, DOF>, Matrix3<f32>, Vector3<f32>) {
        let Frames { rotations: rots, origins, flange_rotation: r, flange_origin: p } = self.frames(q);
        let r_ht = quat::to_rotation_matrix(&flange_to_tool.rotation);
        let p_tool = p + r * flange_to_tool.translation.vector;
        let r_tool = r * r_ht;
        let mut j = SMatrix::<f32, 6, DOF>::zeros();
        for (((ri, pi), joint), mut col) in
            rots.iter().zip(origins.iter()).zip(self.joints.iter()).zip(j.column_iter_mut())
        {
            let z = ri.column(2).into_owned();
            match joint.kind {
                JointKind::Revolute => {
                    let v = z.cross(&(p_tool - pi));
                    col.copy_from_slice(&[v.x, v.y, v.z, z.x, z.y, z.z]);
                }
                JointKind::Prismatic => col.copy_from_slice(&[z.x, z.y, z.z, 0.0, 0.0, 0.0]),
            }
        }
        (j, r_tool, p_tool)
    }

    /// Largest absolute difference between [`Chain::jacobian_at`] and central differences of
    /// the tool pose with joint step `h` (linear rows: `Δp / 2h`; angular rows: the axial vector
    /// of `ΔR Rᵀ / 2h`). A check of the analytic Jacobian against the forward kinematics, shared
    /// by the core's and the host's tests; NaN when a pose is not finite.
    pub fn jacobian_finite_difference_error(&self, q: &[f32; DOF], flange_to_tool: &Isometry3<f32>, h: f32) -> f32 {
        let (j, r0, _) = self.jacobian_at(q, flange_to_tool);
        let mut worst = 0.0f32;
        for (i, col) in j.column_iter().enumerate() {
            let (mut qp, mut qm) = (*q, *q);
            if let (Some(a), Some(b)) = (qp.get_mut(i), qm.get_mut(i)) {
                *a += h;
                *b -= h;
            }
            let (_, rp, pp) = self.jacobian_at(&qp, flange_to_tool);
            let (_, rm, pm) = self.jacobian_at(&qm, flange_to_tool);
            let v = (pp - pm) / (2.0 * h);
            let s = (rp - rm) / (2.0 * h) * r0.transpose();
            let fd = [v.x, v.y, v.z, s.m32, s.m13, s.m21];
            for (a, b) in col.iter().zip(fd.iter()) {
                let d = (a - b).abs();
                if d.is_nan() {
                    return f32::NAN;
                }
                worst = worst.max(d);
            }
        }
        worst
    }

    /// Geometric Jacobian of the flange itself.
    pub fn jacobian(&self, q: &[f32; DOF]) -> SMatrix<f32, 6, DOF> {
        self.jacobian_at(q, &Isometry3::identity()).0
    }

    /// Whether every joint is within its limits (false for NaN).
    pub fn within_limits(&self, q: &[f32; DOF]) -> bool {
        self.joints.iter().zip(q.iter()).all(|(j, qi)| *qi >= j.q_min && *qi <= j.q_max)
    }
}

/// `lo ≤ hi`, neither NaN (infinities allowed).
fn limits_ordered(lo: f32, hi: f32) -> bool {
    !lo.is_nan() && !hi.is_nan() && lo <= hi
}

fn check_frame(f: &Frame, part: ChainPart) -> Result<(), ChainError> {
    if !f.is_finite() {
        Err(ChainError::NotFinite(part))
    } else if !f.is_rigid() {
        Err(ChainError::NotRigid(part))
    } else {
        Ok(())
    }
}

/// `R · Rz(q)`: the first two columns turn, the third stays.
fn rotate_about_z(r: &Matrix3<f32>, q: f32) -> Matrix3<f32> {
    let (s, c) = math::sin_cos(q);
    let (x, y) = (r.column(0), r.column(1));
    let nx = x * c + y * s;
    let ny = y * c - x * s;
    Matrix3::from_columns(&[nx, ny, r.column(2).into_owned()])
}

/// An isometry from a rotation matrix (assumed orthonormal) and a translation.
pub fn isometry(r: &Matrix3<f32>, t: &Vector3<f32>) -> Isometry3<f32> {
    let q = quat::from_rotation_matrix(r).unwrap_or_else(|_| UnitQuaternion::identity());
    Isometry3::from_parts(Translation3::from(*t), q)
}

/// The joint frames of a chain at one configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frames<const DOF: usize> {
    /// Rotation of joint `i`'s frame before its motion (its `z` is the joint axis).
    pub rotations: [Matrix3<f32>; DOF],
    /// Origin of joint `i`'s frame (a point on the joint axis).
    pub origins: [Vector3<f32>; DOF],
    /// Flange rotation.
    pub flange_rotation: Matrix3<f32>,
    /// Flange origin.
    pub flange_origin: Vector3<f32>,
}
