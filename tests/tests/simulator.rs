//! Simulator checks spanning the core and the simulator: feedforward accuracy on short runs,
//! ground truth (the model at the true pose fits the rendered frames; the arm's forward
//! kinematics is the camera pose the renderer used), and scenario validation.

use evorec_core::board::CameraController;
use evorec_core::fitness::Evaluator;
use evorec_core::hue::HueLut;
use evorec_core::image::Rgb565Image;
use evorec_core::kinematics::PA10;
use evorec_core::limits::DEFAULT_GRID;
use evorec_core::model::SurfaceStrips;
use evorec_core::tuning::Feedforward;
use evorec_sim::experiments::experiment::{self, Accuracy};
use evorec_sim::sim::board::{self as sim, SimBoard, World};
use evorec_sim::sim::motion::MotionKind;
use evorec_sim::sim::scenario::Scenario;
use nalgebra::Isometry3;

/// 5 s of a motion at ω = 0.5 rad/s (4× the paper's base speed), default camera and target.
fn short(motion: MotionKind, method: Feedforward) -> Scenario {
    let mut s = Scenario::new(1, 5.0, method);
    s.robot.motion = motion;
    s.robot.omega_rad_s = 0.5;
    s
}

fn run(s: &Scenario) -> Accuracy {
    experiment::run(s, || {}).unwrap_or_else(|e| panic!("run failed: {e:#}")).summary.accuracy
}

#[test]
fn feedforward_tracks_motion_a_and_b_accurately() {
    for motion in [MotionKind::A, MotionKind::B] {
        let a = run(&short(motion, Feedforward::On));
        println!("{motion:?} ff: {a:?}");
        assert_eq!(a.rms.frames, 153);
        assert!(a.f_mean >= 0.9, "{motion:?}: F_mean {}", a.f_mean);
        for (name, v) in [("x", a.rms.rms_x_mm), ("y", a.rms.rms_y_mm), ("z", a.rms.rms_z_mm)] {
            assert!(v <= 3.0, "{motion:?}: RMS {name} = {v} mm");
        }
        for (name, v) in [("e1", a.rms.rms_e1), ("e2", a.rms.rms_e2), ("e3", a.rms.rms_e3)] {
            assert!(v <= 0.005, "{motion:?}: RMS {name} = {v}");
        }
    }
}

#[test]
fn camera_like_light_is_tracked_with_the_learnt_colours() {
    // `scenarios/camera_like.toml` (motion A at 0.5 rad/s with feedforward under shading, a
    // highlight, a cast shadow, a filmic tone curve, a white-balance error, chroma noise, motion
    // blur and JPEG), 3 s. With the configured hues alone its true pose scores about 0.5.
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/camera_like.toml");
    let mut s = Scenario::load(&path).unwrap();
    s.duration_s = 3.0;
    let a = run(&s);
    println!("camera-like: {a:?}");
    assert!(a.f_mean >= 0.9, "F_mean {}", a.f_mean);
    for (name, v) in [("x", a.rms.rms_x_mm), ("y", a.rms.rms_y_mm)] {
        assert!(v <= 1.0, "RMS {name} = {v} mm");
    }
    // The pale faces' edges bias depth by about +2 mm (docs/method.md).
    assert!(a.rms.rms_z_mm <= 4.0, "RMS z = {} mm", a.rms.rms_z_mm);
    for (name, v) in [("e1", a.rms.rms_e1), ("e2", a.rms.rms_e2), ("e3", a.rms.rms_e3)] {
        assert!(v <= 0.005, "RMS {name} = {v}");
    }
}

#[test]
fn feedforward_is_not_worse_than_the_plain_ga() {
    for motion in [MotionKind::A, MotionKind::B] {
        let ff = run(&short(motion, Feedforward::On));
        let ga = run(&short(motion, Feedforward::Off));
        let pos = |a: &Accuracy| a.rms.rms_x_mm + a.rms.rms_y_mm + a.rms.rms_z_mm;
        let eps = |a: &Accuracy| a.rms.rms_e1 + a.rms.rms_e2 + a.rms.rms_e3;
        println!("{motion:?}: ff {ff:?}\n   ga {ga:?}");
        assert!(ff.f_mean >= ga.f_mean, "{motion:?}: F_mean ff {} < ga {}", ff.f_mean, ga.f_mean);
        assert!(pos(&ff) <= pos(&ga), "{motion:?}: position RMS ff {} > ga {}", pos(&ff), pos(&ga));
        assert!(eps(&ff) <= eps(&ga), "{motion:?}: ε RMS ff {} > ga {}", eps(&ff), eps(&ga));
    }
}

#[test]
fn model_at_the_true_pose_fits_clean_rendered_frames() {
    for motion in [MotionKind::A, MotionKind::B] {
        let mut s = short(motion, Feedforward::On);
        s.camera.noise_std = 0.0;
        s.duration_s = 2.0;
        let rig = sim::rig(&s).expect("rig");
        let model = SurfaceStrips::<DEFAULT_GRID>::new(&sim::block(&s)).expect("model");
        let lut = HueLut::new(&model.faces().map(|f| f.hue), evorec_core::limits::DEFAULT_HUE_TOLERANCE);
        let eval = Evaluator::new(&model, &lut, &rig);
        let mut board = SimBoard::new(World::new(&s).expect("world")).expect("board");
        let n = sim::image_bytes(&s);
        let (mut l, mut r) = (vec![0u8; n], vec![0u8; n]);
        let mut worst = 1.0f32;
        for _ in 0..board.frames() {
            board.next_frame(&mut l, &mut r).expect("frame");
            let truth = board.world().truth();
            let (w, h) = (s.camera.width, s.camera.height);
            let left = Rgb565Image::new_checked(&l[..], w, h).expect("image");
            let right = Rgb565Image::new_checked(&r[..], w, h).expect("image");
            let f = eval.evaluate_psi(&truth, &left, &right);
            if f.total < 0.95 {
                println!("t={:.3} {:?} {:?} truth {:?}", board.world().time(), f.left, f.right, truth);
            }
            worst = worst.min(f.total);
        }
        println!("{motion:?}: worst F at the true pose {worst}");
        assert!(worst >= 0.95, "{motion:?}: F at the true pose dropped to {worst}");
    }
}

#[test]
fn arm_forward_kinematics_is_the_rendered_camera_pose() {
    let s = short(MotionKind::B, Feedforward::On);
    let mut world = World::new(&s).expect("world");
    for k in 1..=10 {
        world.advance_to(0.4 * f64::from(k));
        let q = world.arm().joint_sample().q;
        // Independent path: the core's f32 DH chain and the scenario's camera mount.
        let camera: Isometry3<f32> = PA10.forward(&q) * sim::flange_to_camera(&s);
        let used: Isometry3<f32> = world.camera_pose().cast();
        let dp = (camera.translation.vector - used.translation.vector).norm();
        let dr = camera.rotation.angle_to(&used.rotation);
        assert!(dp < 1e-5 && dr < 1e-5, "t = {}: {dp} m, {dr} rad", world.time());
        // And the true pose is the target seen from that camera.
        let truth = world.truth().try_to_isometry().expect("pose");
        let target: Isometry3<f32> = world.target_pose().cast();
        let from_fk = camera.inverse() * target;
        assert!((from_fk.translation.vector - truth.translation.vector).norm() < 1e-5);
    }
}

#[test]
fn scenario_errors_name_the_field() {
    let ok = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../scenarios/smoke.toml")).expect("smoke");
    for (from, to, field) in [
        ("width = 640", "width = 0", "camera.width"),
        ("motion = \"A\"", "motion = \"C\"", "robot.motion"),
        ("method = \"ff\"", "method = \"fast\"", "tracker.method"),
        ("population = 40", "population = 1", "tracker.ga.population"),
        ("population = 40", "population = 7", "tracker.acquire.seed_immigrants"),
        ("size_m = [0.1, 0.15, 0.2]", "size_m = [0.1, 0.15]", "target.size_m"),
    ] {
        assert!(ok.contains(from), "{from}");
        let err = Scenario::from_toml_str(&ok.replacen(from, to, 1)).expect_err(to);
        let msg = err.to_string();
        assert!(msg.starts_with(&format!("{field}:")), "{to}: {msg}");
    }
    assert!(Scenario::from_toml_str(&ok).is_ok());
}

#[test]
fn a_manoeuvring_block_is_reported_tracking_only_where_the_pose_is_right() {
    // The sideways reversing belt (`scenarios/conveyor_ff_target.toml`), GA seed 6, 15 s: the
    // block is held throughout, on poses more than 10 mm or 5° off on a dozen frames or more (33
    // measured; the first of seeds 1–12 whose first 15 s hold wrong poses without losing the
    // block). Those are `uncertain`, not `tracking` (docs/method.md, "A status that states its
    // accuracy").
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios/conveyor_ff_target.toml");
    let mut s = Scenario::load(&path).unwrap();
    (s.seed, s.duration_s) = (6, 15.0);
    let out = experiment::run(&s, || {}).unwrap_or_else(|e| panic!("run failed: {e:#}"));
    let wrong = |r: &sim::TraceRow| {
        let (mm, deg) = evorec_sim::experiments::acquire::pose_error(&r.estimate, &r.truth);
        mm > 10.0 || deg > 5.0
    };
    let held_wrong = out.rows.iter().filter(|r| r.status.holds() && wrong(r)).count();
    let (w, c) = (out.summary.wrong_tracking, out.summary.status);
    println!("held and wrong {held_wrong}; {w:?}; {c:?}");
    assert!(held_wrong >= 10, "the scene should hold wrong poses: {held_wrong}");
    assert!(w.tracking_frames >= 150, "tracking on {} frames only", w.tracking_frames);
    assert!(200 * w.tracking_wrong_frames <= w.tracking_frames, "{w:?}");
    assert_eq!(c.searching + c.lost, 0, "{c:?}");
}
