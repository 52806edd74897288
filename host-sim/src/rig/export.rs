//! `evorec export`: a simulator scenario written as a recorded sequence (`evorec-seq/1`).
//!
//! The simulated world runs exactly as in `evorec run` (same 1 ms control steps, same renders
//! in the same order, so the same image noise), and is written out as a rig would record it:
//! the PA-10's URDF ([`crate::recording::robot::PA10_URDF`]), camera_info YAMLs (principal point shifted
//! to the camera_info convention), the images the simulated RGB565 sensor delivered as 8-bit
//! PNGs ([`crate::sim::render::sensor_rgb`]: what `evorec track` reads gives the very hue the
//! simulator's tracker looked up), the joint state at every control
//! step (1 kHz), the true pose as `groundtruth.tum`, and `sequence.toml` with the true pose at
//! frame 0 as `initial_pose` and the simulator's search box.
//!
//! Times are written in whole microseconds (`{:.6}`), so a frame captured on a control step
//! (any frame period that is a multiple of 1 ms, e.g. the default 0.033 s) has a joint
//! sample at exactly its capture time and `evorec track` gives it the very `q, q̇` the
//! simulator gave the tracker. Joint values are written with Rust's shortest round-trip
//! formatting, so they read back bit for bit. For other frame periods the simulator hands the
//! tracker the state of the nearest control step while `evorec track` interpolates to the
//! capture time: the joint states then differ by at most `|q̇|·0.5 ms`.
//!
//! The sequence is written into `OUT.partial` and renamed to `OUT` when complete
//! ([`crate::output::io::write_dir`]), so an interrupted export never leaves a directory that looks
//! like a sequence.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use indicatif::ProgressBar;

use crate::recording::robot::{ArmModel, PA10_BASE_LINK, PA10_FLANGE_LINK, PA10_URDF};
use crate::recording::sequence::write::{ManifestFields, joints_header, joints_row, manifest_text};
use crate::recording::sequence::{camera_info, tum};
use crate::sim::arm::CONTROL_PERIOD_S;
use crate::sim::board::{self as sim, World, search_space};
use crate::sim::motion;
use crate::sim::render;
use crate::sim::scenario::Scenario;

/// What an export wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ExportStats {
    /// Stereo frames.
    pub frames: usize,
    /// Joint samples.
    pub joint_samples: usize,
}

/// Writes scenario `s` as a sequence directory `out` (which must not exist or be empty).
///
/// # Errors
/// An existing non-empty `out`, I/O errors, an invalid scenario.
pub fn export(s: &Scenario, name: &str, out: &Path, progress: Option<ProgressBar>) -> Result<ExportStats> {
    crate::output::io::write_dir(out, |dir| write_sequence(s, name, dir, progress))
}

fn write_file(dir: &Path, rel: &str, text: &str) -> Result<()> {
    crate::output::io::write_file_in(dir, rel, text.as_bytes())
}

fn write_sequence(s: &Scenario, name: &str, dir: &Path, progress: Option<ProgressBar>) -> Result<ExportStats> {
    let mut world = World::new(s)?;
    let rig = *world.rig();
    write_file(dir, "robot.urdf", PA10_URDF)?;
    for (file, cam, cam_name) in [("calib/left.yaml", &rig.left, "left"), ("calib/right.yaml", &rig.right, "right")] {
        let yaml = camera_info::to_yaml(&camera_info::from_pinhole(cam, cam_name)).map_err(anyhow::Error::msg)?;
        write_file(dir, file, &yaml)?;
    }
    write_file(dir, "sequence.toml", &manifest(s, name, &world))?;
    std::fs::create_dir_all(dir.join("left"))?;
    std::fs::create_dir_all(dir.join("right"))?;

    let arm_model = ArmModel::from_urdf_str(PA10_URDF, PA10_BASE_LINK, PA10_FLANGE_LINK, "robot::PA10_URDF")?;
    let mut joints = joints_header(&arm_model.joint_names);
    let mut frames = String::from("index,t_s,left,right\n");
    let mut truth = Vec::new();
    let mut samples = 0;
    let mut record = |world: &World, joints: &mut String| {
        let a = world.arm();
        joints_row(joints, &format!("{:.6}", a.time()), a.q(), a.qd());
        samples += 1;
    };
    record(&world, &mut joints);
    let total = sim::frame_total(s);
    for n in 0..total {
        let t = f64::from(n) * s.frame_period_s;
        // The steps of `World::advance_to(t)`, one at a time, each one recorded.
        while world.time() + 0.5 * CONTROL_PERIOD_S < t {
            world.advance_to(world.time() + CONTROL_PERIOD_S);
            record(&world, &mut joints);
        }
        let images = world.render();
        let (l, r) = (format!("left/{n:06}.png"), format!("right/{n:06}.png"));
        crate::output::io::write_png(&dir.join(&l), &render::sensor_rgb(&images.left))?;
        crate::output::io::write_png(&dir.join(&r), &render::sensor_rgb(&images.right))?;
        let _ = writeln!(frames, "{n},{t:.6},{l},{r}");
        truth.push((t, world.target_in_camera()));
        if let Some(p) = &progress {
            p.inc(1);
        }
    }
    // One more step, so the last frame's capture time lies within the joint samples.
    world.advance_to(world.time() + CONTROL_PERIOD_S);
    record(&world, &mut joints);
    write_file(dir, "joints.csv", &joints)?;
    write_file(dir, "frames.csv", &frames)?;
    let gt = tum::format(
        "t tx ty tz qx qy qz qw: true pose of the block in the right camera frame (^CR T_M), metres",
        &truth,
    );
    write_file(dir, "groundtruth.tum", &gt)?;
    Ok(ExportStats { frames: total as usize, joint_samples: samples })
}

fn manifest(s: &Scenario, name: &str, world: &World) -> String {
    let pose = world.target_in_camera();
    let (t, q) = (pose.translation.vector, pose.rotation.coords);
    let space = search_space();
    let to64 = |a: [f32; 3]| a.map(f64::from);
    manifest_text(&ManifestFields {
        name,
        comment: "",
        stamp_origin_s: None,
        base_link: PA10_BASE_LINK,
        flange_link: PA10_FLANGE_LINK,
        right_to_left: world.rig().left_from_right.cast(),
        flange_to_right: motion::flange_to_camera_f64(s.camera.baseline_m),
        size_m: s.target.size_m,
        face_hues_deg: s.target.face_hues_deg,
        initial_pose: Some(([t.x, t.y, t.z], [q.x, q.y, q.z, q.w])),
        search: Some((to64(space.t_min()), to64(space.t_max()))),
    })
}
