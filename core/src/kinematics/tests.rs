use super::reference::CASES;
use super::*;
use nalgebra::{Isometry3, Matrix3, SMatrix, Translation3, UnitQuaternion, Vector3};

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
        let e = PA10.jacobian_finite_difference_error(&c.q, &tool, 1e-3);
        assert!(e < 2e-3, "{:?}: {e}", c.q);
    }
}

#[test]
fn limits() {
    assert!(PA10.within_limits(&[0.0; 7]));
    assert!(!PA10.within_limits(&[0.0, 1.7, 0.0, 0.0, 0.0, 0.0, 0.0]));
}

/// Largest absolute difference of flange pose and Jacobian between two chains at `q`.
fn max_difference<const DOF: usize>(a: &Chain<DOF>, b: &Chain<DOF>, q: &[f32; DOF]) -> f32 {
    let (ra, pa) = a.forward_rp(q);
    let (rb, pb) = b.forward_rp(q);
    let dj = (a.jacobian(q) - b.jacobian(q)).abs().max();
    (ra - rb).abs().max().max((pa - pb).abs().max()).max(dj)
}

/// A few configurations spread over the joint ranges.
fn configurations<const DOF: usize>() -> [[f32; DOF]; 5] {
    core::array::from_fn(|k| core::array::from_fn(|i| math::sin(1.3 * (k * DOF + i) as f32 + 0.4) * 2.0))
}

#[test]
fn pa10_literal_equals_its_dh_table() {
    let from_dh = Chain::from_dh(&PA10_DH);
    for c in &CASES {
        assert!(max_difference(&PA10, &from_dh, &c.q) <= 1e-6);
    }
    for q in &configurations::<7>() {
        let d = max_difference(&PA10, &from_dh, q);
        assert!(d <= 1e-6, "{q:?}: {d}");
    }
    assert!(PA10.validate().is_ok());
    assert!(from_dh.within_limits(&[0.0; 7]));
}

/// A DH table in the style of a 6-DOF industrial arm (non-zero `a`, offsets).
const SIX_DH: [DhLink; 6] = [
    DhLink { d: 0.4, a: 0.025, alpha: -core::f32::consts::FRAC_PI_2, offset: 0.0, q_min: -3.0, q_max: 3.0 },
    DhLink { d: 0.0, a: 0.455, alpha: 0.0, offset: -core::f32::consts::FRAC_PI_2, q_min: -2.0, q_max: 2.0 },
    DhLink { d: 0.0, a: 0.035, alpha: -core::f32::consts::FRAC_PI_2, offset: 0.0, q_min: -2.5, q_max: 2.5 },
    DhLink { d: 0.42, a: 0.0, alpha: core::f32::consts::FRAC_PI_2, offset: 0.0, q_min: -3.0, q_max: 3.0 },
    DhLink { d: 0.0, a: 0.0, alpha: -core::f32::consts::FRAC_PI_2, offset: 0.0, q_min: -2.0, q_max: 2.0 },
    DhLink { d: 0.08, a: 0.0, alpha: 0.0, offset: 0.3, q_min: -6.0, q_max: 6.0 },
];

/// DH forward kinematics written directly from the definition, as an independent check.
fn dh_forward<const DOF: usize>(links: &[DhLink; DOF], q: &[f32; DOF]) -> (Matrix3<f32>, Vector3<f32>) {
    let mut r = Matrix3::identity();
    let mut p = Vector3::zeros();
    for (l, qi) in links.iter().zip(q.iter()) {
        let (st, ct) = math::sin_cos(qi + l.offset);
        let (sa, ca) = math::sin_cos(l.alpha);
        let rl = Matrix3::new(ct, -st * ca, st * sa, st, ct * ca, -ct * sa, 0.0, sa, ca);
        p += r * Vector3::new(l.a * ct, l.a * st, l.d);
        r *= rl;
    }
    (r, p)
}

#[test]
fn six_dof_dh_chain_matches_the_dh_definition_and_finite_differences() {
    let chain = Chain::from_dh(&SIX_DH);
    for q in &configurations::<6>() {
        let (r, p) = chain.forward_rp(q);
        let (rw, pw) = dh_forward(&SIX_DH, q);
        assert!((r - rw).abs().max() <= 1e-6 && (p - pw).abs().max() <= 1e-6);
        check_jacobian_by_finite_differences(&chain, q, &Isometry3::identity());
    }
}

/// Central differences of the tool pose against the analytic Jacobian.
fn check_jacobian_by_finite_differences<const DOF: usize>(chain: &Chain<DOF>, q: &[f32; DOF], tool: &Isometry3<f32>) {
    let e = chain.jacobian_finite_difference_error(q, tool, 1e-3);
    assert!(e < 2e-3, "{q:?}: {e}");
}

fn spec(origin: Frame, axis: [f32; 3], kind: JointKind) -> JointSpec {
    JointSpec { origin, axis, kind, q_min: -2.0, q_max: 2.0 }
}

fn frame(angle: f32, axis: [f32; 3], t: [f32; 3]) -> Frame {
    let q = quat::from_angle_axis(angle, &Vector3::from(axis)).unwrap();
    Frame::from_isometry(&Isometry3::from_parts(Translation3::from(Vector3::from(t)), q))
}

/// Forward kinematics straight from the joint specs: `O_i · Rot(axis_i, q_i)` or
/// `O_i · Trans(axis_i q_i)`, by isometries.
fn spec_forward<const DOF: usize>(specs: &[JointSpec; DOF], tip: &Frame, q: &[f32; DOF]) -> Isometry3<f32> {
    let mut t = Isometry3::identity();
    for (s, qi) in specs.iter().zip(q.iter()) {
        let axis = Vector3::from(s.axis).normalize();
        let motion = match s.kind {
            JointKind::Revolute => {
                Isometry3::from_parts(Translation3::identity(), quat::from_angle_axis(*qi, &axis).unwrap())
            }
            JointKind::Prismatic => Isometry3::from_parts(Translation3::from(axis * *qi), UnitQuaternion::identity()),
        };
        t = t * s.origin.to_isometry() * motion;
    }
    t * tip.to_isometry()
}

/// A 7-joint chain with axes in every direction (including ±z) and two prismatic joints.
fn mixed_specs() -> ([JointSpec; 7], Frame) {
    let specs = [
        spec(Frame::translation(0.0, 0.0, 0.2), [0.0, 0.0, 1.0], JointKind::Revolute),
        spec(frame(0.3, [1.0, 0.0, 0.0], [0.0, 0.1, 0.3]), [0.0, 1.0, 0.0], JointKind::Revolute),
        spec(frame(-0.7, [0.2, 1.0, 0.1], [0.3, 0.0, 0.0]), [0.0, 0.6, 0.8], JointKind::Prismatic),
        spec(Frame::translation(0.0, 0.05, 0.25), [0.0, 0.0, -1.0], JointKind::Revolute),
        spec(frame(1.2, [0.0, 0.0, 1.0], [0.1, 0.0, 0.1]), [1.0, 0.0, 0.0], JointKind::Prismatic),
        spec(frame(2.0, [1.0, 1.0, 0.0], [0.0, 0.0, 0.15]), [-0.48, 0.6, -0.64], JointKind::Revolute),
        spec(Frame::translation(0.0, 0.0, 0.08), [0.0, 0.0, 1.0], JointKind::Revolute),
    ];
    (specs, frame(0.5, [0.0, 1.0, 1.0], [0.02, -0.03, 0.05]))
}

#[test]
fn checked_chain_with_any_axes_and_prismatic_joints_matches_direct_composition() {
    let (specs, tip) = mixed_specs();
    let chain = Chain::new_checked(&specs, &tip).unwrap();
    let tool = frame(0.4, [1.0, 2.0, 0.5], [0.03, -0.05, 0.1]).to_isometry();
    for q in &configurations::<7>() {
        let want = spec_forward(&specs, &tip, q);
        let got = chain.forward(q);
        assert!((got.translation.vector - want.translation.vector).abs().max() <= 2e-6);
        assert!(got.rotation.angle_to(&want.rotation) <= 2e-5);
        check_jacobian_by_finite_differences(&chain, q, &tool);
    }
    // Prismatic columns are pure translation along the axis.
    let j = chain.jacobian(&[0.1; 7]);
    for col in [2, 4] {
        assert_eq!([j[(3, col)], j[(4, col)], j[(5, col)]], [0.0; 3]);
        assert!((Vector3::new(j[(0, col)], j[(1, col)], j[(2, col)]).norm() - 1.0).abs() < 1e-6);
    }
}

#[test]
fn a_purely_prismatic_chain_translates_along_its_axes() {
    let specs = [
        spec(Frame::IDENTITY, [1.0, 0.0, 0.0], JointKind::Prismatic),
        spec(Frame::IDENTITY, [0.0, 1.0, 0.0], JointKind::Prismatic),
        spec(Frame::translation(0.0, 0.0, 0.5), [0.0, 0.0, -1.0], JointKind::Prismatic),
    ];
    let chain = Chain::new_checked(&specs, &Frame::IDENTITY).unwrap();
    let (r, p) = chain.forward_rp(&[0.25, -0.5, 0.125]);
    assert!((r - Matrix3::identity()).abs().max() <= 1e-7);
    assert_eq!([p.x, p.y, p.z], [0.25, -0.5, 0.375]);
    let j = chain.jacobian(&[0.0; 3]);
    let want = SMatrix::<f32, 6, 3>::from_row_slice(&[
        1.0, 0.0, 0.0, //
        0.0, 1.0, 0.0, //
        0.0, 0.0, -1.0, //
        0.0, 0.0, 0.0, //
        0.0, 0.0, 0.0, //
        0.0, 0.0, 0.0,
    ]);
    assert!((j - want).abs().max() <= 1e-7);
}

#[test]
fn checked_chain_normalises_nearly_unit_axes_and_rejects_bad_data() {
    let (specs, tip) = mixed_specs();
    let mut s = specs;
    s[1].axis = [0.0, 1.0005, 0.0];
    assert!(Chain::new_checked(&s, &tip).is_ok());

    let bad = |f: &dyn Fn(&mut [JointSpec; 7], &mut Frame)| {
        let (mut s, mut t) = mixed_specs();
        f(&mut s, &mut t);
        Chain::new_checked(&s, &t).unwrap_err()
    };
    assert_eq!(bad(&|s, _| s[2].axis = [0.0; 3]), ChainError::AxisNotUnit(2));
    assert_eq!(bad(&|s, _| s[2].axis = [0.0, 0.0, 1.1]), ChainError::AxisNotUnit(2));
    assert_eq!(bad(&|s, _| s[0].axis = [f32::NAN, 0.0, 1.0]), ChainError::NotFinite(ChainPart::Joint(0)));
    assert_eq!(bad(&|s, _| s[3].origin.translation[1] = f32::INFINITY), ChainError::NotFinite(ChainPart::Joint(3)));
    assert_eq!(bad(&|s, _| s[4].origin.rotation[0][0] = 1.1), ChainError::NotRigid(ChainPart::Joint(4)));
    assert_eq!(bad(&|_, t| t.rotation[2][2] = -1.0), ChainError::NotRigid(ChainPart::Tip));
    assert_eq!(bad(&|s, _| (s[5].q_min, s[5].q_max) = (1.0, -1.0)), ChainError::LimitsNotOrdered(5));
    assert_eq!(bad(&|s, _| s[6].q_max = f32::NAN), ChainError::LimitsNotOrdered(6));
    // A mirror is orthonormal but not a rotation.
    let mirror = Frame { rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]], translation: [0.0; 3] };
    assert_eq!(bad(&|s, _| s[1].origin = mirror), ChainError::NotRigid(ChainPart::Joint(1)));
    // Continuous joints: no limits.
    let (mut s, t) = mixed_specs();
    (s[0].q_min, s[0].q_max) = (f32::NEG_INFINITY, f32::INFINITY);
    let chain = Chain::new_checked(&s, &t).unwrap();
    assert!(chain.within_limits(&[1e6, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
}

#[test]
fn kinematics_never_panics_on_any_q() {
    let (specs, tip) = mixed_specs();
    let chain = Chain::new_checked(&specs, &tip).unwrap();
    for v in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY, f32::MAX, -f32::MIN_POSITIVE, 1e30] {
        let q = [v; 7];
        let _ = chain.forward(&q);
        let _ = chain.jacobian_at(&q, &Isometry3::identity());
        let _ = PA10.forward(&q);
        assert!(!PA10.within_limits(&q) || v.is_finite());
    }
}
