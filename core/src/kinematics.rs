//! Serial-chain kinematics with standard (distal) Denavit–Hartenberg parameters
//! (paper §3, eq. 20–21).
//!
//! Joint `i` contributes `T_i = Rz(q_i + offset_i) · Tz(d_i) · Tx(a_i) · Rx(α_i)`; the flange
//! pose is `T_1 ⋯ T_DOF`. All joints are revolute about the `z` axis of the previous frame.
//! [`PA10`] is the Mitsubishi PA-10 (7 DOF) with the lengths of the manufacturer's model.

use nalgebra::{Isometry3, Matrix3, SMatrix, Translation3, UnitQuaternion, Vector3};

use crate::{math, quat};

/// One link's DH parameters and joint limits (radians, metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DhLink {
    /// Offset along the previous `z` (m).
    pub d: f32,
    /// Length along the new `x` (m).
    pub a: f32,
    /// Twist about the new `x` (rad).
    pub alpha: f32,
    /// Constant added to the joint variable (rad).
    pub offset: f32,
    /// Lower joint limit (rad).
    pub q_min: f32,
    /// Upper joint limit (rad).
    pub q_max: f32,
}

/// A chain of `DOF` revolute joints.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Chain<const DOF: usize> {
    /// The links, base to flange.
    pub links: [DhLink; DOF],
}

const fn deg(x: f32) -> f32 {
    x * (core::f32::consts::PI / 180.0)
}

const fn pa10_link(d: f32, alpha: f32, limit_deg: f32) -> DhLink {
    DhLink { d, a: 0.0, alpha, offset: 0.0, q_min: -deg(limit_deg), q_max: deg(limit_deg) }
}

/// The PA-10: S1, S2, S3, E1, E2, W1, W2; at `q = 0` the arm points straight up with the
/// flange at (0, 0, 1.345) m.
pub const PA10: Chain<7> = {
    use core::f32::consts::FRAC_PI_2;
    Chain {
        links: [
            pa10_link(0.315, -FRAC_PI_2, 177.0),
            pa10_link(0.0, FRAC_PI_2, 94.0),
            pa10_link(0.450, -FRAC_PI_2, 174.0),
            pa10_link(0.0, FRAC_PI_2, 137.0),
            pa10_link(0.500, -FRAC_PI_2, 255.0),
            pa10_link(0.0, FRAC_PI_2, 165.0),
            pa10_link(0.080, 0.0, 255.0),
        ],
    }
};

impl DhLink {
    /// `T_i(q)` of this link.
    pub fn transform(&self, q: f32) -> Isometry3<f32> {
        let (sq, cq) = math::sin_cos(q + self.offset);
        let (sa, ca) = math::sin_cos(self.alpha);
        let r = Matrix3::new(cq, -sq * ca, sq * sa, sq, cq * ca, -cq * sa, 0.0, sa, ca);
        let t = Vector3::new(self.a * cq, self.a * sq, self.d);
        isometry(&r, &t)
    }
}

/// An isometry from a rotation matrix (assumed orthonormal) and a translation.
pub fn isometry(r: &Matrix3<f32>, t: &Vector3<f32>) -> Isometry3<f32> {
    let q = quat::from_rotation_matrix(r).unwrap_or_else(|_| UnitQuaternion::identity());
    Isometry3::from_parts(Translation3::from(*t), q)
}

/// The joint frames of a chain at one configuration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frames<const DOF: usize> {
    /// Rotation of frame `i − 1` (whose `z` is joint `i`'s axis), `i = 1..=DOF`.
    pub rotations: [Matrix3<f32>; DOF],
    /// Origin of frame `i − 1`.
    pub origins: [Vector3<f32>; DOF],
    /// Flange rotation.
    pub flange_rotation: Matrix3<f32>,
    /// Flange origin.
    pub flange_origin: Vector3<f32>,
}

impl<const DOF: usize> Chain<DOF> {
    /// The frames `T_0 = I, T_0·T_1, …, T_0⋯T_DOF` as rotation and origin, by matrix
    /// products (no quaternion round trip, so no rounding beyond the products).
    pub fn frames(&self, q: &[f32; DOF]) -> Frames<DOF> {
        let mut rots = [Matrix3::identity(); DOF];
        let mut origins = [Vector3::zeros(); DOF];
        let mut r = Matrix3::identity();
        let mut p = Vector3::zeros();
        for ((link, qi), (ri, pi)) in self.links.iter().zip(q.iter()).zip(rots.iter_mut().zip(origins.iter_mut())) {
            *ri = r;
            *pi = p;
            let (sq, cq) = math::sin_cos(qi + link.offset);
            let (sa, ca) = math::sin_cos(link.alpha);
            let rl = Matrix3::new(cq, -sq * ca, sq * sa, sq, cq * ca, -cq * sa, 0.0, sa, ca);
            let tl = Vector3::new(link.a * cq, link.a * sq, link.d);
            p += r * tl;
            r *= rl;
        }
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
    /// Column `i`: `J_o,i = z_{i−1}`, `J_p,i = z_{i−1} × (p_tool − p_{i−1})`.
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
        for ((ri, pi), mut col) in rots.iter().zip(origins.iter()).zip(j.column_iter_mut()) {
            let z = ri.column(2).into_owned();
            let v = z.cross(&(p_tool - pi));
            col.copy_from_slice(&[v.x, v.y, v.z, z.x, z.y, z.z]);
        }
        (j, r_tool, p_tool)
    }

    /// Geometric Jacobian of the flange itself.
    pub fn jacobian(&self, q: &[f32; DOF]) -> SMatrix<f32, 6, DOF> {
        self.jacobian_at(q, &Isometry3::identity()).0
    }

    /// Whether every joint is within its limits.
    pub fn within_limits(&self, q: &[f32; DOF]) -> bool {
        self.links.iter().zip(q.iter()).all(|(l, qi)| *qi >= l.q_min && *qi <= l.q_max)
    }
}

/// PA-10 reference values for the tests of this crate.
#[cfg(test)]
#[allow(clippy::excessive_precision, clippy::approx_constant)] // copied verbatim
pub(crate) mod reference {
    /// Reference values from a third-party robotics toolbox
    /// (shared/reference/pa10_fk_vectors.json): q, flange position, rotation (row-major),
    /// Jacobian (6 rows of 7).
    pub(crate) struct Case {
        pub q: [f32; 7],
        pub p: [f32; 3],
        pub r: [f32; 9],
        pub j: [[f32; 7]; 6],
        /// Flange quaternion `[x, y, z, w]`, `w ≥ 0`.
        pub quat_xyzw: [f32; 4],
    }

    pub(crate) const CASES: [Case; 4] = [
        Case {
            q: [0.0; 7],
            p: [0.0, 0.0, 1.345],
            r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
            j: [
                [0.0, 1.03, 0.0, 0.58, 0.0, 0.08, 0.0],
                [0.0; 7],
                [0.0; 7],
                [0.0; 7],
                [0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0],
                [1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 1.0],
            ],
            quat_xyzw: [0.0, 0.0, 0.0, 1.0],
        },
        Case {
            q: [0.1, -0.4, 0.3, 1.2, -0.5, 0.7, 0.2],
            p: [0.2286037161, 0.1594286319, 1.0814767738],
            r: [
                0.1613818846,
                -0.0340020721,
                0.9863061119,
                -0.2551876358,
                0.9639793813,
                0.0749868191,
                -0.9533284627,
                -0.2637946391,
                0.1468919009,
            ],
            j: [
                [-0.1594286319, 0.7626475825, -0.1766417838, 0.3453931326, -0.0000650744, 0.0131936128, 0.0],
                [0.2286037161, 0.0765199951, 0.5075469234, 0.0825307676, 0.0460778513, -0.0353291209, 0.0],
                [0.0, -0.2433779548, -0.0528868516, -0.4368857158, -0.0230853314, -0.0705533968, 0.0],
                [0.0, -0.0998334166, -0.3874728726, -0.3662068141, 0.6481240398, -0.0012626634, 0.9863061119],
                [0.0, 0.9950041653, -0.0388769636, 0.9233899151, 0.3418486399, 0.8940660165, 0.0749868191],
                [1.0, 0.0, 0.9210609940, -0.1150809890, 0.6804959489, -0.4479334369, 0.1468919009],
            ],
            quat_xyzw: [-0.1123728197, 0.6433711207, -0.0733666052, 0.7536997358],
        },
        Case {
            q: [-1.0, 0.6, -0.8, -1.4, 2.0, -1.1, 3.0],
            p: [0.2686105213, 0.1930377525, 1.0179388255],
            r: [
                -0.7089881402,
                0.5102392303,
                -0.4868179791,
                -0.6656479714,
                -0.7121684879,
                0.2229996032,
                -0.2329132782,
                0.4821534742,
                0.8445587204,
            ],
            j: [
                [-0.1930377525, 0.3797994683, -0.4933084378, 0.1244220884, 0.0431476562, 0.0503910380, 0.0],
                [0.2686105213, -0.5915026258, 0.0072429186, -0.3536162394, -0.0435697170, 0.0607590176, 0.0],
                [0.0, 0.0173047837, 0.1865164864, 0.3846550212, 0.0363753090, 0.0130032716, 0.0],
                [0.0, 0.8414709848, 0.3050776304, 0.9061496103, 0.3405420519, -0.6051854216, -0.4868179791],
                [0.0, 0.5403023059, -0.4751302582, -0.1217686745, 0.7780128008, 0.6111052123, 0.2229996032],
                [1.0, 0.0, 0.8253356149, -0.4050497175, 0.5279462024, -0.5101970453, 0.8445587204],
            ],
            quat_xyzw: [0.1991366536, -0.1951031342, -0.9035645174, 0.3253467735],
        },
        Case {
            q: [0.7853981634, 0.5235987756, 0.0, 1.0471975512, 0.0, 0.7853981634, 0.0],
            p: [0.5526524164, 0.5526524164, 0.6481428892],
            r: [-0.5, -0.7071067812, 0.5, -0.5, 0.7071067812, 0.5, -0.7071067812, 0.0, -0.7071067812],
            j: [
                [-0.5526524164, 0.2355675961, -0.3608272340, -0.04, -0.04, -0.04, 0.0],
                [0.5526524164, 0.2355675961, 0.3608272340, -0.04, 0.04, -0.04, 0.0],
                [0.0, -0.7815685425, 0.0, -0.5565685425, 0.0, -0.0565685425, 0.0],
                [0.0, -0.7071067812, 0.3535533906, -0.7071067812, 0.7071067812, -0.7071067812, 0.5],
                [0.0, 0.7071067812, 0.3535533906, 0.7071067812, 0.7071067812, 0.7071067812, 0.5],
                [1.0, 0.0, 0.8660254038, 0.0, 0.0, 0.0, -0.7071067812],
            ],
            quat_xyzw: [-0.3535533906, 0.8535533906, 0.1464466094, 0.3535533906],
        },
    ];
}

#[cfg(test)]
mod tests {
    use super::reference::CASES;
    use super::*;

    const TOL: f32 = 1e-5;

    #[test]
    fn pa10_forward_kinematics_matches_reference() {
        for c in &CASES {
            let (r, p) = PA10.forward_rp(&c.q);
            for i in 0..3 {
                assert!((p[i] - c.p[i]).abs() <= TOL, "p {p} vs {:?}", c.p);
            }
            for (i, want) in c.r.iter().enumerate() {
                assert!((r[(i / 3, i % 3)] - want).abs() <= TOL, "R {r} vs {:?}", c.r);
            }
            let iso = PA10.forward(&c.q);
            assert!((iso.rotation.to_rotation_matrix().into_inner() - r).abs().max() <= TOL);
        }
    }

    #[test]
    fn pa10_jacobian_matches_reference() {
        for c in &CASES {
            let j = PA10.jacobian(&c.q);
            for (row, want_row) in c.j.iter().enumerate() {
                for (col, want) in want_row.iter().enumerate() {
                    assert!((j[(row, col)] - want).abs() <= TOL, "J[{row},{col}] = {} vs {want}", j[(row, col)]);
                }
            }
        }
    }

    #[test]
    fn jacobian_matches_finite_differences_at_a_tool_point() {
        let tool = Isometry3::from_parts(
            Translation3::new(0.03, -0.05, 0.1),
            quat::from_angle_axis(0.4, &Vector3::new(1.0, 2.0, 0.5)).unwrap(),
        );
        for c in &CASES {
            let (j, r0, p0) = PA10.jacobian_at(&c.q, &tool);
            let h = 1e-3f32;
            for i in 0..7 {
                let mut qp = c.q;
                let mut qm = c.q;
                qp[i] += h;
                qm[i] -= h;
                let (_, rp, pp) = PA10.jacobian_at(&qp, &tool);
                let (_, rm, pm) = PA10.jacobian_at(&qm, &tool);
                let v = (pp - pm) / (2.0 * h);
                // S(ω) ≈ Ṙ Rᵀ
                let s = (rp - rm) / (2.0 * h) * r0.transpose();
                let w = Vector3::new(s[(2, 1)], s[(0, 2)], s[(1, 0)]);
                let _ = p0;
                for k in 0..3 {
                    assert!((j[(k, i)] - v[k]).abs() < 2e-3, "Jp[{k},{i}] {} vs {}", j[(k, i)], v[k]);
                    assert!((j[(k + 3, i)] - w[k]).abs() < 2e-3, "Jo[{k},{i}] {} vs {}", j[(k + 3, i)], w[k]);
                }
            }
        }
    }

    #[test]
    fn limits() {
        assert!(PA10.within_limits(&[0.0; 7]));
        assert!(!PA10.within_limits(&[0.0, 1.7, 0.0, 0.0, 0.0, 0.0, 0.0]));
    }
}
