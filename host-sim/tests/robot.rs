//! Arms from URDF: the PA-10's URDF against the core's `PA10`, the KUKA iiwa against the
//! independent ground truth of the `iiwa-sway` sample sequence, Jacobians against finite
//! differences, prismatic and continuous joints, and one clear error per bad file.

use evorec_core::kinematics::{Chain, PA10};
use evorec_sim::recording::robot::{ArmModel, PA10_BASE_LINK, PA10_FLANGE_LINK, PA10_URDF, RobotError};
use nalgebra::{Isometry3, Matrix3, Matrix4, Rotation3, Vector3};

const IIWA_URDF: &str = include_str!("data/iiwa.urdf");
const IIWA_BASE: &str = "lbr_iiwa_link_0";
const IIWA_FLANGE: &str = "lbr_iiwa_link_7";

/// Configurations spread over ±2 rad.
fn configurations<const DOF: usize>() -> Vec<[f32; DOF]> {
    (0..6).map(|k| std::array::from_fn(|i| (1.3 * (k * DOF + i) as f32 + 0.4).sin() * 2.0)).collect()
}

fn iiwa() -> Chain<7> {
    ArmModel::from_urdf_str(IIWA_URDF, IIWA_BASE, IIWA_FLANGE, "iiwa.urdf").unwrap().to_chain().unwrap()
}

#[test]
fn pa10_urdf_gives_the_pa10_chain() {
    let model = ArmModel::from_urdf_str(PA10_URDF, PA10_BASE_LINK, PA10_FLANGE_LINK, "pa10.urdf").unwrap();
    assert_eq!(model.joint_names, ["S1", "S2", "S3", "E1", "E2", "W1", "W2"]);
    assert_eq!(model.dof(), 7);
    let chain: Chain<7> = model.to_chain().unwrap();
    for q in configurations::<7>() {
        let ((r, p), (rw, pw)) = (chain.forward_rp(&q), PA10.forward_rp(&q));
        assert!((r - rw).abs().max() <= 1e-6 && (p - pw).abs().max() <= 1e-6, "{q:?}");
        let dj = (chain.jacobian(&q) - PA10.jacobian(&q)).abs().max();
        assert!(dj <= 1e-6, "{q:?}: {dj}");
    }
    for (a, b) in chain.joints.iter().zip(PA10.joints.iter()) {
        assert!((a.q_min - b.q_min).abs() <= 1e-6 && (a.q_max - b.q_max).abs() <= 1e-6);
    }
}

/// `^H T_CR` of the samples (`flange_to_right` in their `sequence.toml`).
fn flange_to_right() -> Matrix4<f64> {
    Matrix4::new(
        0.0,
        0.99756405026,
        0.069756473744,
        -0.04,
        -1.0,
        0.0,
        0.0,
        -0.05,
        0.0,
        -0.069756473744,
        0.99756405026,
        0.1,
        0.0,
        0.0,
        0.0,
        1.0,
    )
}

/// Rows of `iiwa-sway` copied verbatim: `t`, joint positions (joints.csv, at a sample time
/// that is also a frame time) and the block's pose in the right camera (groundtruth.tum:
/// `tx ty tz qx qy qz qw`).
#[allow(clippy::excessive_precision)]
const SWAY: [(f64, [f32; 7], [f64; 7]); 6] = [
    (
        0.0,
        [
            -0.000000062434,
            0.290576852453,
            0.000000086471,
            -1.636623513612,
            0.000000104619,
            0.271914491598,
            -0.000000025769,
        ],
        [-0.049999944, 0.000000021, 0.698212007, 0.453153871, -0.784885573, 0.365998139, 0.211309177],
    ),
    (
        1.5,
        [
            -0.297656219415,
            0.305897841126,
            0.201798719131,
            -1.622771061063,
            0.174917218772,
            0.286321794413,
            -0.278609588763,
        ],
        [-0.118163858, 0.000000023, 0.698212008, 0.433869583, -0.795707847, 0.371044667, 0.202316735],
    ),
    (
        3.0,
        [
            -0.419311518877,
            0.322581851540,
            0.280082124815,
            -1.606970864874,
            0.241987785183,
            0.302118909875,
            -0.392655029261,
        ],
        [-0.149749474, 0.000000026, 0.698212009, 0.415016248, -0.805701748, 0.375704898, 0.193525285],
    ),
    (
        5.0,
        [
            -0.263448451688,
            0.302449311670,
            0.179158235887,
            -1.625944145335,
            0.155403445345,
            0.283070905997,
            -0.246574087357,
        ],
        [-0.109847186, 0.000000024, 0.698212009, 0.391770570, -0.817257373, 0.381093374, 0.182685650],
    ),
    (
        7.0,
        [
            0.157266585841,
            0.294704555564,
            -0.107694640743,
            -1.632953830716,
            -0.093561319675,
            0.275786911234,
            0.147168355418,
        ],
        [-0.014921668, 0.000000021, 0.698212006, 0.372142843, -0.826379754, 0.385347217, 0.173533078],
    ),
    (
        9.7,
        [
            0.416789375390,
            0.322157271220,
            -0.278503581559,
            -1.607382323091,
            -0.240638579112,
            0.301715126005,
            0.390284541410,
        ],
        [0.049054666, 0.000000060, 0.698212009, 0.353777274, -0.834407223, 0.389090513, 0.164969088],
    ),
];

fn tum_to_matrix(p: &[f64; 7]) -> Matrix4<f64> {
    let q = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(p[6], p[3], p[4], p[5]));
    Isometry3::from_parts(Vector3::new(p[0], p[1], p[2]).into(), q).to_homogeneous()
}

/// Rotation angle of a nearly orthonormal `m` by `atan2(‖skew part‖, (tr − 1)/2)`, which stays
/// accurate for tiny angles (`acos` of the trace alone would turn 1e-7 of rounding into 4e-4 rad).
fn rotation_angle(m: &Matrix3<f64>) -> f64 {
    let s = 0.5 * Vector3::new(m[(2, 1)] - m[(1, 2)], m[(0, 2)] - m[(2, 0)], m[(1, 0)] - m[(0, 1)]);
    s.norm().atan2(0.5 * (m.trace() - 1.0))
}

#[test]
fn iiwa_forward_kinematics_matches_the_sway_samples_ground_truth() {
    let chain = iiwa();
    let mut worst = (0.0f64, 0.0f64);
    for (t, q, gt) in &SWAY {
        let (r, p) = chain.forward_rp(q);
        let mut fk = Matrix4::identity();
        fk.fixed_view_mut::<3, 3>(0, 0).copy_from(&r.cast::<f64>());
        fk.fixed_view_mut::<3, 1>(0, 3).copy_from(&p.cast::<f64>());
        let block = fk * flange_to_right() * tum_to_matrix(gt);
        // The block's fixed pose in the base frame.
        let centre = Vector3::new(1.2, 0.0, 0.1);
        let yaw = (30.0 + 15.0 * (0.125 * t).sin()).to_radians();
        let want = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw);
        let dp = (block.fixed_view::<3, 1>(0, 3) - centre).norm();
        let angle = rotation_angle(&(want.matrix().transpose() * block.fixed_view::<3, 3>(0, 0)));
        assert!(dp <= 1e-4, "t = {t}: position off by {dp} m");
        assert!(angle <= 1e-4, "t = {t}: orientation off by {angle} rad");
        worst = (worst.0.max(dp), worst.1.max(angle));
    }
    eprintln!("iiwa-sway: largest residual {:.2e} m, {:.2e} rad", worst.0, worst.1);
}

/// Central differences of the camera pose against the analytic Jacobian (the core's check).
fn assert_jacobian_matches_finite_differences<const DOF: usize>(
    chain: &Chain<DOF>,
    q: &[f32; DOF],
    tool: &Isometry3<f32>,
) {
    let e = chain.jacobian_finite_difference_error(q, tool, 1e-3);
    assert!(e < 2e-3, "{q:?}: {e}");
}

#[test]
fn iiwa_jacobian_at_the_camera_matches_finite_differences() {
    let chain = iiwa();
    let m = flange_to_right();
    let r = Rotation3::from_matrix_unchecked(Matrix3::from(m.fixed_view::<3, 3>(0, 0)));
    let camera: Isometry3<f32> =
        Isometry3::from_parts(Vector3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]).into(), r.into()).cast();
    for q in configurations::<7>().iter().chain(SWAY.iter().map(|(_, q, _)| q)) {
        assert_jacobian_matches_finite_differences(&chain, q, &camera);
    }
}

/// A 4-joint arm: a prismatic lift along the base's y, a fixed bracket, a continuous joint about
/// a tilted axis, a revolute joint about −x, a prismatic slide along z, and a fixed tool.
const SLIDE_ARM: &str = r#"<?xml version="1.0"?>
<robot name="slide">
  <link name="world"/>
  <link name="base"/>
  <link name="carriage"/>
  <link name="bracket"/>
  <link name="turret"/>
  <link name="arm"/>
  <link name="ram"/>
  <link name="tool"/>
  <joint name="to_base" type="fixed">
    <parent link="world"/><child link="base"/><origin xyz="5 5 5"/>
  </joint>
  <joint name="lift" type="prismatic">
    <parent link="base"/><child link="carriage"/>
    <origin xyz="0.1 0 0.2" rpy="0 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-0.5" upper="0.5" effort="1" velocity="1"/>
  </joint>
  <joint name="mount" type="fixed">
    <parent link="carriage"/><child link="bracket"/><origin xyz="0 0 0.3" rpy="0 0 1.5707963267948966"/>
  </joint>
  <joint name="spin" type="continuous">
    <parent link="bracket"/><child link="turret"/><axis xyz="0 0.6 0.8"/>
  </joint>
  <joint name="tilt" type="revolute">
    <parent link="turret"/><child link="arm"/>
    <origin xyz="0 0 0.25"/><axis xyz="-1 0 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/>
  </joint>
  <joint name="reach" type="prismatic">
    <parent link="arm"/><child link="ram"/>
    <origin xyz="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="0" upper="0.4" effort="1" velocity="1"/>
  </joint>
  <joint name="flange" type="fixed">
    <parent link="ram"/><child link="tool"/><origin xyz="0 0 0.05"/>
  </joint>
</robot>"#;

#[test]
fn prismatic_and_continuous_joints_and_fixed_joints_are_folded() {
    let model = ArmModel::from_urdf_str(SLIDE_ARM, "base", "tool", "slide.urdf").unwrap();
    assert_eq!(model.joint_names, ["lift", "spin", "tilt", "reach"]);
    let chain: Chain<4> = model.to_chain().unwrap();
    assert_eq!((chain.joints[1].q_min, chain.joints[1].q_max), (f32::NEG_INFINITY, f32::INFINITY));
    assert!(!chain.within_limits(&[0.0, 0.0, 0.0, -0.1]));
    // spin = 0, tilt = 0: a straight stack. Lift 0.2 along y, reach 0.3 along the turret's z
    // (the bracket's z), tool 0.05 further.
    let (r, p) = chain.forward_rp(&[0.2, 0.0, 0.0, 0.3]);
    let rz90 = Matrix3::new(0.0, -1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0);
    assert!((r - rz90).abs().max() <= 1e-6, "{r}");
    assert!((p - Vector3::new(0.1, 0.2, 0.2 + 0.3 + 0.25 + 0.3 + 0.05)).abs().max() <= 1e-6, "{p}");
    // tilt = 90° about the bracket's −x (the base's −y, after the 90° yaw) turns the ram
    // from the base's +z to its −x.
    let (_, p) = chain.forward_rp(&[0.0, 0.0, std::f32::consts::FRAC_PI_2, 0.3]);
    assert!((p - Vector3::new(0.1 - 0.35, 0.0, 0.2 + 0.3 + 0.25)).abs().max() <= 1e-6, "{p}");
    // The prismatic columns of the Jacobian are the axes, without rotation.
    let j = chain.jacobian(&[0.0, 0.3, -0.2, 0.1]);
    assert_eq!([j[(3, 0)], j[(4, 0)], j[(5, 0)]], [0.0; 3]);
    assert!((Vector3::new(j[(0, 0)], j[(1, 0)], j[(2, 0)]) - Vector3::y()).abs().max() <= 1e-6);
    for q in configurations::<4>() {
        assert_jacobian_matches_finite_differences(&chain, &q.map(|v| v * 0.2), &Isometry3::identity());
    }
}

/// The message of loading `urdf` (as `bad.urdf`) from `base` to `tool`.
fn error_of(urdf: &str, base: &str, flange: &str) -> String {
    let e: RobotError = ArmModel::from_urdf_str(urdf, base, flange, "bad.urdf").unwrap_err();
    e.to_string()
}

#[test]
fn bad_urdfs_give_one_clear_error_naming_file_and_joint() {
    let e = error_of(&SLIDE_ARM.replace(r#"<axis xyz="-1 0 0"/>"#, r#"<axis xyz="0 0 0"/>"#), "base", "tool");
    assert_eq!(e, "bad.urdf: joint 'tilt': axis (0, 0, 0) is not a unit vector");
    let e = error_of(&SLIDE_ARM.replace(r#"<axis xyz="0 0.6 0.8"/>"#, r#"<axis xyz="0 1 1"/>"#), "base", "tool");
    assert_eq!(e, "bad.urdf: joint 'spin': axis (0, 1, 1) is not a unit vector");
    let e = error_of(&SLIDE_ARM.replace(r#"type="continuous""#, r#"type="floating""#), "base", "tool");
    assert!(e.starts_with("bad.urdf: joint 'spin': type floating is not supported"), "{e}");
    let e = error_of(&SLIDE_ARM.replace(r#"type="continuous""#, r#"type="planar""#), "base", "tool");
    assert!(e.starts_with("bad.urdf: joint 'spin': type planar is not supported"), "{e}");
    let e = error_of(SLIDE_ARM, "base", "gripper");
    assert_eq!(e, "bad.urdf: link 'gripper' does not exist");
    let e = error_of(SLIDE_ARM, "tool", "base");
    assert_eq!(e, "bad.urdf: link 'base': is not below 'tool' (walking up from it ends at 'world')");
    let e = error_of(&SLIDE_ARM.replace(r#"lower="-1" upper="1""#, r#"lower="1" upper="-1""#), "base", "tool");
    assert!(e.starts_with("bad.urdf: joint 'tilt': limits lower 1 upper -1 are not an interval"), "{e}");
    let e = error_of(&SLIDE_ARM.replace(r#"<origin xyz="0 0 0.25"/>"#, r#"<origin xyz="0 0 NaN"/>"#), "base", "tool");
    assert!(e.starts_with("bad.urdf: joint 'tilt': origin xyz (0, 0, NaN)"), "{e}");
    let e = error_of("<robot name='x'><link name='a'/>", "a", "a");
    assert!(e.starts_with("bad.urdf: not a valid URDF"), "{e}");
    // A second parent for a link on the chain.
    let twice = SLIDE_ARM.replace(
        "</robot>",
        r#"<joint name="extra" type="fixed"><parent link="world"/><child link="arm"/></joint></robot>"#,
    );
    assert_eq!(
        error_of(&twice, "base", "tool"),
        "bad.urdf: link 'arm': is the child of two joints ('tilt' and 'extra')"
    );
    // DOF mismatch and a missing file.
    let model = ArmModel::from_urdf_str(SLIDE_ARM, "base", "tool", "slide.urdf").unwrap();
    let e = model.to_chain::<6>().unwrap_err().to_string();
    assert_eq!(e, "slide.urdf: the chain from 'base' to 'tool' has 4 movable joints, 6 are needed");
    let e = ArmModel::from_urdf_file("/nonexistent/robot.urdf", "a", "b").unwrap_err().to_string();
    assert!(e.starts_with("/nonexistent/robot.urdf: cannot read"), "{e}");
}

#[test]
fn urdf_file_on_disk_loads() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/iiwa.urdf");
    let model = ArmModel::from_urdf_file(path, IIWA_BASE, IIWA_FLANGE).unwrap();
    assert_eq!(model.joint_names, (1..=7).map(|i| format!("lbr_iiwa_joint_{i}")).collect::<Vec<_>>());
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../robots/pa10.urdf");
    let model = ArmModel::from_urdf_file(path, PA10_BASE_LINK, PA10_FLANGE_LINK).unwrap();
    assert_eq!(
        model.to_chain::<7>().unwrap(),
        ArmModel::from_urdf_str(PA10_URDF, "base_link", "flange_link", "x").unwrap().to_chain().unwrap()
    );
}
