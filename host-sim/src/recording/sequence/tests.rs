//! Reader tests on small sequences written into temporary directories (each test breaks one
//! thing of a valid sequence and checks the one error it gets).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};

use image::{ImageBuffer, Luma, Rgb, Rgba};

use super::*;

const W: u32 = 8;
const H: u32 = 6;

const URDF: &str = r#"<?xml version="1.0"?>
<robot name="two">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="tool"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0 0 0.2" rpy="0 0 0"/><axis xyz="0 1 0"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="fix" type="fixed"><parent link="l2"/><child link="tool"/><origin xyz="0 0 0.05" rpy="0 0 0"/></joint>
</robot>
"#;

const TOML: &str = r#"format = "evorec-seq/1"
name = "tiny"

[robot]
urdf = "robot.urdf"
base_link = "base"
flange_link = "tool"

[cameras]
left = "calib/left.yaml"
right = "calib/right.yaml"
right_to_left = [1, 0, 0, 0.1,  0, 1, 0, 0,  0, 0, 1, 0,  0, 0, 0, 1]
flange_to_right = [1, 0, 0, 0.05,  0, 1, 0, 0,  0, 0, 1, 0.05,  0, 0, 0, 1]

[target]
size_m = [0.1, 0.15, 0.2]
face_hues_deg = [0, 120, 240, 0, 120, 240]
initial_pose = { t_m = [0.0, 0.0, 0.7], q_xyzw = [0, 0, 0, 1] }
"#;

fn yaml(cx: f64, d: &str) -> String {
    format!(
        "image_width: {W}\nimage_height: {H}\ncamera_name: cam\ncamera_matrix:\n  rows: 3\n  cols: 3\n  data: [10.0, 0.0, {cx}, 0.0, 10.0, 2.5, 0.0, 0.0, 1.0]\n\
         distortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [{d}]\n\
         rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\n\
         projection_matrix:\n  rows: 3\n  cols: 4\n  data: [10.0, 0.0, {cx}, 0.0, 0.0, 10.0, 2.5, 0.0, 0.0, 0.0, 1.0, 0.0]\n"
    )
}

const FRAMES: &str =
    "index,t_s,left,right\n0,0.0,left/0.png,right/0.png\n1,0.1,left/1.png,right/1.png\n2,0.2,left/2.png,right/2.png\n";
const JOINTS: &str = "t_s,pos_j1,pos_j2,vel_j1,vel_j2\n0.0,0.0,1.0,0.5,0.0\n0.08,0.04,1.0,0.5,0.0\n0.16,0.08,0.8,0.5,-2.0\n0.24,0.12,0.6,0.5,-2.0\n";
const GT: &str = "# t tx ty tz qx qy qz qw\n0.0 0 0 0.7 0 0 0 1\n0.1 0 0 0.7 0 0 0 1\n0.2 0 0 0.7 0 0 0 1\n";

fn write(dir: &Path, rel: &str, text: &str) {
    let p = dir.join(rel);
    std::fs::create_dir_all(p.parent().unwrap()).unwrap();
    std::fs::write(p, text).unwrap();
}

/// A valid 3-frame sequence of a 2-joint arm with 8×6 images.
fn valid() -> (tempfile::TempDir, PathBuf) {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path().join("seq");
    write(&dir, "sequence.toml", TOML);
    write(&dir, "robot.urdf", URDF);
    write(&dir, "calib/left.yaml", &yaml(3.5, "0, 0, 0, 0, 0"));
    write(&dir, "calib/right.yaml", &yaml(3.5, "0.0, 0.0, 0.0, 0.0, 0.0"));
    write(&dir, "frames.csv", FRAMES);
    write(&dir, "joints.csv", JOINTS);
    write(&dir, "groundtruth.tum", GT);
    for i in 0..3 {
        for side in ["left", "right"] {
            std::fs::create_dir_all(dir.join(side)).unwrap();
            let img = ImageBuffer::from_pixel(W, H, Rgb([200u8, 10, 10]));
            img.save(dir.join(format!("{side}/{i}.png"))).unwrap();
        }
    }
    (tmp, dir)
}

/// Loads `dir` expecting an error; returns its one-line text.
fn error_of(dir: &Path) -> String {
    let e = Sequence::load(dir).expect_err("the sequence should be refused");
    let text = e.to_string();
    assert!(!text.contains('\n'), "one line: {text}");
    text
}

fn replace(dir: &Path, rel: &str, from: &str, to: &str) {
    let p = dir.join(rel);
    let s = std::fs::read_to_string(&p).unwrap();
    assert!(s.contains(from), "{from} in {rel}");
    std::fs::write(p, s.replacen(from, to, 1)).unwrap();
}

#[test]
fn a_valid_sequence_loads() {
    let (_tmp, dir) = valid();
    let s = Sequence::load(&dir).unwrap();
    assert_eq!(s.name(), "tiny");
    assert_eq!(s.robot.joint_names, ["j1", "j2"]);
    assert_eq!(s.frames.len(), 3);
    assert_eq!(s.frames[2].line, 4);
    assert_eq!(s.image_size(), (W, H));
    assert_eq!(s.groundtruth.as_ref().unwrap().len(), 3);
    assert_eq!(s.rig.left_from_right.translation.vector.x, 0.1);
    let (l, r) = s.decode(1).unwrap();
    assert_eq!((l.dimensions(), r.get_pixel(0, 0).0), ((W, H), [200, 10, 10]));
}

#[test]
fn camera_info_centre_is_shifted_half_a_pixel_into_the_core_convention() {
    let (_tmp, dir) = valid();
    let s = Sequence::load(&dir).unwrap();
    // camera_info cx = 3.5 is the centre of an 8-pixel-wide image; the core's centre is 4.0.
    assert_eq!((s.rig.right.cx(), s.rig.right.cy()), (4.0, 3.0));
    // A point on the optical axis lands on the boundary between pixels 3 and 4 in both.
    let uv = s.rig.right.project(&nalgebra::Point3::new(0.0, 0.0, 1.0)).unwrap();
    assert_eq!((uv.x, uv.y), (4.0, 3.0));
    // The centre of pixel (0, 0) is (0, 0) in camera_info and (0.5, 0.5) in the core.
    let p = nalgebra::Point3::new((0.0 - 3.5) / 10.0, (0.0 - 2.5) / 10.0, 1.0);
    let uv = s.rig.right.project(&p).unwrap();
    assert!((uv.x - 0.5).abs() < 1e-6 && (uv.y - 0.5).abs() < 1e-6);
    // And back.
    let info = camera_info::from_pinhole(&s.rig.right, "r");
    assert_eq!((info.camera_matrix.data[2], info.camera_matrix.data[5]), (3.5, 2.5));
    assert_eq!(camera_info::to_pinhole(&info).unwrap(), s.rig.right);
}

#[test]
fn joint_state_is_interpolated_linearly_at_the_capture_time() {
    let (_tmp, dir) = valid();
    let s = Sequence::load(&dir).unwrap();
    // Frame 1 at 0.1 s lies a quarter of the way from the sample at 0.08 to the one at 0.16.
    let j = s.joints_at_frame(1);
    let close = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| (x - y).abs() < 1e-12);
    assert!(close(&j.q, &[0.05, 0.95]), "{:?}", j.q);
    assert!(close(&j.qd, &[0.5, -0.5]), "{:?}", j.qd);
    // A capture time on a sample takes it exactly; the ends are inside; outside is None.
    assert_eq!(s.joints.at(0.16).unwrap(), JointState { q: vec![0.08, 0.8], qd: vec![0.5, -2.0] });
    assert_eq!(s.joints.at(0.24).unwrap().q, vec![0.12, 0.6]);
    assert_eq!(s.joints.at(0.0).unwrap().q, vec![0.0, 1.0]);
    assert!(s.joints.at(0.2400001).is_none() && s.joints.at(-1e-9).is_none() && s.joints.at(f64::NAN).is_none());
}

#[test]
fn missing_files_are_named() {
    let (_tmp, dir) = valid();
    std::fs::remove_file(dir.join("joints.csv")).unwrap();
    let e = error_of(&dir);
    assert!(e.contains("joints.csv") && e.contains("cannot read"), "{e}");

    let (_tmp, dir) = valid();
    std::fs::remove_file(dir.join("right/2.png")).unwrap();
    let e = error_of(&dir);
    assert!(e.contains("right/2.png") && e.contains("frame 2") && e.contains("line 4"), "{e}");

    let (_tmp, dir) = valid();
    std::fs::remove_file(dir.join("calib/left.yaml")).unwrap();
    assert!(error_of(&dir).contains("calib/left.yaml"));
}

#[test]
fn image_size_and_pixel_format_are_checked_on_decoding() {
    let (_tmp, dir) = valid();
    ImageBuffer::from_pixel(W + 1, H, Rgb([1u8, 2, 3])).save(dir.join("left/1.png")).unwrap();
    let s = Sequence::load(&dir).unwrap();
    let e = s.decode(1).unwrap_err().to_string();
    assert!(e.contains("left/1.png") && e.contains("9x6") && e.contains("8x6"), "{e}");
    // RGBA is accepted, grey and 16-bit are not, nor is a file that is not a PNG.
    ImageBuffer::from_pixel(W, H, Rgba([200u8, 10, 10, 7])).save(dir.join("left/1.png")).unwrap();
    assert_eq!(s.decode(1).unwrap().0.get_pixel(3, 3).0, [200, 10, 10]);
    ImageBuffer::from_pixel(W, H, Luma([9u8])).save(dir.join("left/1.png")).unwrap();
    assert!(s.decode(1).unwrap_err().to_string().contains("not supported"));
    ImageBuffer::from_pixel(W, H, Rgb([9u16, 9, 9])).save(dir.join("left/1.png")).unwrap();
    assert!(s.decode(1).unwrap_err().to_string().contains("Rgb16"));
    std::fs::write(dir.join("left/1.png"), b"no png").unwrap();
    assert!(s.decode(1).unwrap_err().to_string().contains("not a readable PNG"));
}

#[test]
fn joint_names_must_match_the_urdf_chain() {
    let (_tmp, dir) = valid();
    replace(&dir, "joints.csv", "pos_j1,pos_j2", "pos_j2,pos_j1");
    let e = error_of(&dir);
    assert!(e.contains("joints.csv:1") && e.contains("pos_j1,pos_j2,vel_j1,vel_j2"), "{e}");
    let (_tmp, dir) = valid();
    replace(&dir, "sequence.toml", "flange_link = \"tool\"", "flange_link = \"nowhere\"");
    let e = error_of(&dir);
    assert!(e.contains("robot.urdf") && e.contains("nowhere"), "{e}");
}

#[test]
fn non_finite_and_bad_numbers_in_csv_name_the_line_and_column() {
    let (_tmp, dir) = valid();
    replace(&dir, "joints.csv", "0.08,0.04,1.0", "0.08,NaN,1.0");
    let e = error_of(&dir);
    assert!(e.contains("joints.csv:3: pos_j1") && e.contains("not finite"), "{e}");
    let (_tmp, dir) = valid();
    replace(&dir, "frames.csv", "1,0.1,", "1,inf,");
    assert!(error_of(&dir).contains("frames.csv:3: t_s"));
    let (_tmp, dir) = valid();
    replace(&dir, "joints.csv", "0.16,0.08,0.8,0.5,-2.0", "0.16,0.08,0.8,0.5");
    let e = error_of(&dir);
    assert!(e.contains("joints.csv") && e.contains("line 4") || e.contains("joints.csv:4"), "{e}");
}

#[test]
fn frames_outside_the_joint_samples_are_refused() {
    let (_tmp, dir) = valid();
    replace(&dir, "frames.csv", "2,0.2,", "2,0.25,");
    let e = error_of(&dir);
    assert!(e.contains("frames.csv:4: t_s") && e.contains("outside the joint samples"), "{e}");
}

#[test]
fn times_must_increase() {
    let (_tmp, dir) = valid();
    replace(&dir, "frames.csv", "2,0.2,", "2,0.1,");
    assert!(error_of(&dir).contains("frames.csv:4: t_s"));
    let (_tmp, dir) = valid();
    replace(&dir, "joints.csv", "0.16,", "0.08,");
    assert!(error_of(&dir).contains("joints.csv:4: t_s"));
    let (_tmp, dir) = valid();
    replace(&dir, "groundtruth.tum", "0.2 0 0", "0.1 0 0");
    assert!(error_of(&dir).contains("groundtruth.tum:4"));
}

#[test]
fn non_rigid_transforms_are_refused() {
    let (_tmp, dir) = valid();
    replace(&dir, "sequence.toml", "[1, 0, 0, 0.05,", "[1.1, 0, 0, 0.05,");
    let e = error_of(&dir);
    assert!(e.contains("sequence.toml: cameras.flange_to_right: not a rigid transform"), "{e}");
    let (_tmp, dir) = valid();
    replace(&dir, "sequence.toml", "0, 0, 1, 0,  0, 0, 0, 1]", "0, 0, -1, 0,  0, 0, 0, 1]");
    assert!(error_of(&dir).contains("cameras.right_to_left: not a rigid transform"));
}

#[test]
fn malformed_toml_yaml_and_tum_are_located() {
    let (_tmp, dir) = valid();
    replace(&dir, "sequence.toml", "[target]", "[target]\nsize = 3");
    let e = error_of(&dir);
    assert!(e.contains("sequence.toml:16") && e.contains("unknown field"), "{e}");
    let (_tmp, dir) = valid();
    replace(&dir, "sequence.toml", "base_link = \"base\"", "base_link = base");
    assert!(error_of(&dir).contains("sequence.toml:6"));
    let (_tmp, dir) = valid();
    replace(&dir, "sequence.toml", "evorec-seq/1", "evorec-seq/2");
    assert!(error_of(&dir).contains("format: expected \"evorec-seq/1\""));
    let (_tmp, dir) = valid();
    replace(&dir, "calib/right.yaml", "  rows: 3\n  cols: 3\n  data: [10.0", "  rows: 3\n  cols: [3\n  data: [10.0");
    let e = error_of(&dir);
    assert!(e.contains("calib/right.yaml:"), "{e}");
    let (_tmp, dir) = valid();
    replace(&dir, "calib/right.yaml", "image_height: 6\n", "");
    assert!(error_of(&dir).contains("image_height"));
    let (_tmp, dir) = valid();
    replace(&dir, "groundtruth.tum", "0.1 0 0 0.7 0 0 0 1", "0.1 0 0 0.7 0 0 1");
    assert!(error_of(&dir).contains("groundtruth.tum:3: expected 8 numbers"));
    let (_tmp, dir) = valid();
    replace(&dir, "groundtruth.tum", "0.1 0 0 0.7 0 0 0 1", "0.1 0 0 0.7 0 0 0 2");
    assert!(error_of(&dir).contains("groundtruth.tum:3: quaternion is not unit"));
    let (_tmp, dir) = valid();
    replace(&dir, "groundtruth.tum", "0.1 0 0 0.7", "0.15 0 0 0.7");
    assert!(error_of(&dir).contains("no pose at frame 1"));
}

#[test]
fn lens_distortion_reaches_the_core_camera() {
    let (_tmp, dir) = valid();
    replace(&dir, "calib/left.yaml", "data: [0, 0, 0, 0, 0]", "data: [0.1, -0.02, 0.001, 0.002, 0.003]");
    let s = Sequence::load(&dir).unwrap();
    assert_eq!(s.rig.left.distortion().apply(0.0, 0.0), (0.0, 0.0));
    let (x, y) = s.rig.left.distortion().apply(0.2, -0.1);
    assert!((x - 0.2).abs() > 1e-4 && (y + 0.1).abs() > 1e-4, "distortion not applied: {x} {y}");
    assert_eq!(s.rig.right.distortion().apply(0.2, -0.1), (0.2, -0.1));
    replace(&dir, "calib/left.yaml", "data: [0.1, -0.02, 0.001, 0.002, 0.003]", "data: [0.1, 0, 0, 0]");
    let e = error_of(&dir);
    assert!(e.contains("calib/left.yaml: distortion_coefficients") && e.contains("expected 5 values"), "{e}");
}

#[test]
fn left_and_right_sizes_must_agree() {
    let (_tmp, dir) = valid();
    replace(&dir, "calib/right.yaml", "image_width: 8", "image_width: 10");
    assert!(error_of(&dir).contains("one size"));
}

#[test]
fn bad_target_and_search_values_name_the_field() {
    let (_tmp, dir) = valid();
    replace(&dir, "sequence.toml", "size_m = [0.1,", "size_m = [-0.1,");
    assert!(error_of(&dir).contains("target.size_m[0]"));
    let (_tmp, dir) = valid();
    replace(&dir, "sequence.toml", "q_xyzw = [0, 0, 0, 1]", "q_xyzw = [0, 0, 0, 3]");
    assert!(error_of(&dir).contains("target.initial_pose: q_xyzw must be a unit quaternion"));
    let (_tmp, dir) = valid();
    let text = std::fs::read_to_string(dir.join("sequence.toml")).unwrap();
    write(&dir, "sequence.toml", &(text + "\n[search]\nmin_m = [-0.1, -0.1, 0.8]\nmax_m = [0.1, 0.1, 1.0]\n"));
    assert!(error_of(&dir).contains("outside [search]"));
}
