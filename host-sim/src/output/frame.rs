//! `evorec render`: one frame's images, the projected search model over them (as the paper's
//! Fig. 4), and the frame's geometry and each visible face's colour statistics
//! ([`render::face_stats`]) as JSON.

use std::path::{Path, PathBuf};

use anyhow::Result;
use evorec_core::camera::Pinhole;
use evorec_core::limits::DEFAULT_GRID;
use evorec_core::model::SurfaceStrips;
use nalgebra::{Isometry3, Matrix4, Point3};
use serde::Serialize;

use crate::sim::board::{self as sim, world_at_frame};
use crate::sim::render;
use crate::sim::scenario::Scenario;

#[derive(Serialize)]
struct Intrinsics {
    fx: f32,
    fy: f32,
    cx: f32,
    cy: f32,
    width: u16,
    height: u16,
}

impl From<&Pinhole> for Intrinsics {
    fn from(c: &Pinhole) -> Self {
        Self { fx: c.fx(), fy: c.fy(), cx: c.cx(), cy: c.cy(), width: c.width(), height: c.height() }
    }
}

/// `frame.json`: 4×4 matrices are row-major, metres.
#[derive(Serialize)]
struct FrameJson {
    frame: u32,
    t: f64,
    left_intrinsics: Intrinsics,
    right_intrinsics: Intrinsics,
    left_from_right: [[f64; 4]; 4],
    q: [f32; 7],
    qd: [f32; 7],
    world_from_flange: [[f64; 4]; 4],
    flange_from_camera: [[f64; 4]; 4],
    world_from_target: [[f64; 4]; 4],
    camera_from_target: [[f64; 4]; 4],
    true_psi: [f32; 6],
    /// HSV statistics of each visible face's pixels in the left and right image.
    face_stats: FaceStatsPair,
}

#[derive(Serialize)]
struct FaceStatsPair {
    left: Vec<render::FaceStats>,
    right: Vec<render::FaceStats>,
}

fn rows(m: Matrix4<f64>) -> [[f64; 4]; 4] {
    core::array::from_fn(|r| core::array::from_fn(|c| m[(r, c)]))
}

fn mat(iso: &Isometry3<f64>) -> [[f64; 4]; 4] {
    rows(iso.to_homogeneous())
}

/// Renders frame `n` of `s` into `out`; returns the files written.
///
/// # Errors
/// Frame past the end of the scenario, or I/O errors.
pub fn render_frame(s: &Scenario, n: u32, out: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(out)?;
    let mut world = world_at_frame(s, n)?;
    let images = world.render();
    let rig = *world.rig();
    let model = SurfaceStrips::<DEFAULT_GRID>::new(world.block()).map_err(|e| anyhow::anyhow!("model: {e}"))?;
    let pose: Isometry3<f32> = world.target_in_camera().cast();
    let mut written = Vec::new();
    for (name, img, cam, cam_from_model) in
        [("left", &images.left, rig.left, rig.left_from_right * pose), ("right", &images.right, rig.right, pose)]
    {
        let path = out.join(format!("{name}.png"));
        crate::output::io::write_png(&path, img)?;
        written.push(path);
        let mut overlay = img.clone();
        let project = |p: Point3<f32>| cam.project(&(cam_from_model * p)).ok().map(|uv| (uv.x, uv.y));
        // Only the faces turned towards this camera, as the fitness uses them.
        for k in 0..6 {
            let n_cam = cam_from_model.rotation * evorec_core::model::Block::normal(k);
            let c = cam_from_model * Point3::from(evorec_core::model::Block::normal(k) * model.half_size()[k % 3]);
            if n_cam.dot(&c.coords) >= 0.0 {
                continue;
            }
            let inner: Vec<_> = model.inner_points(k).filter_map(project).collect();
            let outer: Vec<_> = model.outer_points(k).filter_map(project).collect();
            render::draw_points(&mut overlay, &inner, [255, 255, 255]);
            render::draw_points(&mut overlay, &outer, [0, 0, 0]);
        }
        let path = out.join(format!("{name}_model.png"));
        crate::output::io::write_png(&path, &overlay)?;
        written.push(path);
    }
    let joints = world.arm().joint_sample();
    let json = FrameJson {
        frame: n,
        t: world.time(),
        left_intrinsics: (&rig.left).into(),
        right_intrinsics: (&rig.right).into(),
        left_from_right: mat(&rig.left_from_right.cast()),
        q: joints.q,
        qd: joints.qd,
        world_from_flange: mat(&world.arm().flange_pose()),
        flange_from_camera: mat(&sim::flange_to_camera(s).cast()),
        world_from_target: mat(&world.target_pose()),
        camera_from_target: mat(&world.target_in_camera()),
        true_psi: world.truth().0,
        face_stats: FaceStatsPair {
            left: render::face_stats(&images.left, &rig.left, &(rig.left_from_right * pose), world.block()),
            right: render::face_stats(&images.right, &rig.right, &pose, world.block()),
        },
    };
    let path = out.join("frame.json");
    crate::output::io::write_json(&path, &json)?;
    written.push(path);
    Ok(written)
}
