//! Recorded stereo sequences in the `evorec-seq/1` format: the reader.
//!
//! A sequence directory holds `sequence.toml` (the only file that names the others), the
//! arm's URDF, two ROS camera_info YAML files, one PNG per camera and frame, `frames.csv`,
//! `joints.csv` and optionally `groundtruth.tum` (the layout and its conventions are described
//! in `docs/own-rig.md`).
//!
//! [`Sequence::load`] reads and checks **all** metadata: every bad input is one
//! [`SequenceError`] naming the file and, where it applies, the line and the field — a missing
//! file (images included: every frame's two PNGs must exist), malformed TOML/YAML/CSV/TUM,
//! unknown keys in `sequence.toml`, a 4×4 that is not rigid, joint columns that do not name
//! the URDF chain's movable joints in order, NaN/inf in a CSV, times that do not increase, a
//! frame captured outside the joint samples, a left/right size mismatch. Image sizes and
//! pixel formats are checked when a PNG is decoded ([`Sequence::decode`]).
//!
//! ## Crates
//! - `toml` + serde for `sequence.toml`, `csv` for the tables, `image` for PNG, `urdf-rs`
//!   for the URDF.
//! - YAML: **`serde-saphyr`**. `serde_yaml` is deprecated and unmaintained; its forks
//!   `serde_yaml_ng` and `serde_norway` keep the `unsafe-libyaml` C-to-Rust translation.
//!   `serde-saphyr` is a maintained pure-Rust parser (saphyr) that never panics on input,
//!   reports the line and column of an error (used in our messages), and names ROS among
//!   its targets; it is dual MIT/Apache-2.0 like this project.

pub mod camera_info;
pub mod error;
pub mod images;
pub mod manifest;
pub mod robot;
pub mod tables;
pub mod tum;
pub mod write;

#[cfg(test)]
mod tests;

use std::path::{Path, PathBuf};

use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::model::Block;
use image::RgbImage;
use nalgebra::Isometry3;

pub use error::{Result, SequenceError};
pub use robot::Robot;
pub use tables::{FrameRow, JointState, JointTable};

/// Ground truth may be matched to a frame whose capture time differs by at most this (s).
pub const TIME_MATCH_S: f64 = 1e-6;

/// A sequence whose metadata has been read and checked.
#[derive(Debug, Clone)]
pub struct Sequence {
    /// The sequence directory.
    pub dir: PathBuf,
    /// `sequence.toml`, validated.
    pub manifest: manifest::Checked,
    /// The stereo rig (core conventions; see [`camera_info`] for the pixel shift).
    pub rig: StereoRig,
    /// The arm.
    pub robot: Robot,
    /// The target block.
    pub block: Block,
    /// `frames.csv`.
    pub frames: Vec<FrameRow>,
    /// `joints.csv`.
    pub joints: JointTable,
    /// `^CR T_M` per frame from `groundtruth.tum` (same order as `frames`), when present.
    pub groundtruth: Option<Vec<Isometry3<f64>>>,
}

impl Sequence {
    /// Reads and checks every file of the sequence at `dir` except the image contents.
    ///
    /// # Errors
    /// The first bad input found, as one [`SequenceError`].
    pub fn load(dir: &Path) -> Result<Self> {
        if !dir.is_dir() {
            return Err(SequenceError::file(dir, "is not a sequence directory"));
        }
        let manifest = manifest::load(&dir.join("sequence.toml"))?;
        let raw = &manifest.raw;
        let (left_path, right_path) = (dir.join(&raw.cameras.left), dir.join(&raw.cameras.right));
        let (_, left) = camera_info::load(&left_path)?;
        let (_, right) = camera_info::load(&right_path)?;
        check_sizes(&left, &right, &left_path, &right_path)?;
        let rig = StereoRig { right, left, left_from_right: manifest.right_to_left.cast() };
        let robot = Robot::load(&dir.join(&raw.robot.urdf), &raw.robot.base_link, &raw.robot.flange_link)?;
        let frames_path = dir.join("frames.csv");
        let frames = tables::read_frames(&frames_path, dir)?;
        let joints = JointTable::read(&dir.join("joints.csv"), &robot.joint_names)?;
        check_frames(&frames_path, &frames, &joints)?;
        let gt_path = dir.join("groundtruth.tum");
        let groundtruth = if gt_path.exists() { Some(match_groundtruth(&gt_path, &frames)?) } else { None };
        let block = Block {
            size_m: raw.target.size_m.map(|v| v as f32),
            face_hues_deg: raw.target.face_hues_deg.map(|v| v as f32),
        };
        Ok(Self { dir: dir.to_path_buf(), manifest, rig, robot, block, frames, joints, groundtruth })
    }

    /// A sequence held in memory (what `evorec import` writes and `evorec track BAG` tracks):
    /// the text of `sequence.toml`, of both camera_info YAMLs and of the URDF, parsed and
    /// checked as [`Sequence::load`] does, with frames and joints already read. `dir` is where
    /// the files would be (it only names them in errors and in the frames' image paths).
    ///
    /// # Errors
    /// As [`Sequence::load`], naming the file the text would be.
    pub fn from_memory(dir: &Path, files: &Texts<'_>, frames: Vec<FrameRow>, joints: JointTable) -> Result<Self> {
        let manifest = manifest::parse(files.manifest, &dir.join("sequence.toml"))?;
        let raw = &manifest.raw;
        let (_, left) = camera_info::parse(files.left_yaml, &dir.join(&raw.cameras.left))?;
        let (_, right) = camera_info::parse(files.right_yaml, &dir.join(&raw.cameras.right))?;
        check_sizes(&left, &right, &dir.join(&raw.cameras.left), &dir.join(&raw.cameras.right))?;
        let rig = StereoRig { right, left, left_from_right: manifest.right_to_left.cast() };
        let urdf = dir.join(&raw.robot.urdf);
        let robot = Robot::from_urdf_str(files.urdf, &raw.robot.base_link, &raw.robot.flange_link, &urdf)?;
        if joints.names() != robot.joint_names.as_slice() {
            return Err(SequenceError::file(dir.join("joints.csv"), "joints do not name the URDF chain's joints"));
        }
        check_times(&dir.join("frames.csv"), &frames, &joints)?;
        let block = Block {
            size_m: raw.target.size_m.map(|v| v as f32),
            face_hues_deg: raw.target.face_hues_deg.map(|v| v as f32),
        };
        Ok(Self { dir: dir.to_path_buf(), manifest, rig, robot, block, frames, joints, groundtruth: None })
    }

    /// The sequence's name (`name` in `sequence.toml`, else the directory's name).
    pub fn name(&self) -> String {
        let n = &self.manifest.raw.name;
        if n.is_empty() {
            self.dir.file_name().map_or_else(String::new, |s| s.to_string_lossy().into_owned())
        } else {
            n.clone()
        }
    }

    /// The image size of both cameras.
    pub fn image_size(&self) -> (u32, u32) {
        (u32::from(self.rig.right.width()), u32::from(self.rig.right.height()))
    }

    /// Decodes frame `i`'s left and right PNGs.
    ///
    /// # Errors
    /// Unreadable PNG, wrong pixel format or size (naming the file).
    pub fn decode(&self, i: usize) -> Result<(RgbImage, RgbImage)> {
        decode_pair(&self.frames[i], &self.rig.left, &self.rig.right)
    }

    /// The joint state at frame `i`'s capture time (checked to exist by [`Sequence::load`]).
    pub fn joints_at_frame(&self, i: usize) -> JointState {
        // Checked at load time; an empty state would be refused by the tracker as non-finite.
        self.joints.at(self.frames[i].t_s).unwrap_or(JointState { q: vec![f64::NAN; self.joints.dof()], qd: vec![] })
    }
}

/// Decodes a frame's two PNGs (left, right).
///
/// # Errors
/// As [`images::decode`].
pub fn decode_pair(frame: &FrameRow, left: &Pinhole, right: &Pinhole) -> Result<(RgbImage, RgbImage)> {
    let (l, r) = rayon::join(
        || images::decode(&frame.left, u32::from(left.width()), u32::from(left.height())),
        || images::decode(&frame.right, u32::from(right.width()), u32::from(right.height())),
    );
    Ok((l?, r?))
}

/// The text of a sequence's files, for [`Sequence::from_memory`].
#[derive(Debug, Clone, Copy)]
pub struct Texts<'a> {
    /// `sequence.toml`.
    pub manifest: &'a str,
    /// The left camera_info YAML.
    pub left_yaml: &'a str,
    /// The right camera_info YAML.
    pub right_yaml: &'a str,
    /// The URDF.
    pub urdf: &'a str,
}

fn check_sizes(left: &Pinhole, right: &Pinhole, left_path: &Path, right_path: &Path) -> Result<()> {
    if (left.width(), left.height()) != (right.width(), right.height()) {
        return Err(SequenceError::file(
            left_path,
            format!(
                "left camera is {}x{} but the right one ({}) is {}x{}: both images of a pair must have one size",
                left.width(),
                left.height(),
                right_path.display(),
                right.width(),
                right.height()
            ),
        ));
    }
    Ok(())
}

/// Every frame's images exist and its capture time lies within the joint samples.
fn check_frames(path: &Path, frames: &[FrameRow], joints: &JointTable) -> Result<()> {
    check_times(path, frames, joints)?;
    for f in frames {
        for (side, img) in [("left", &f.left), ("right", &f.right)] {
            if !img.is_file() {
                return Err(SequenceError::file(
                    img,
                    format!("missing: the {side} image of frame {} (frames.csv line {})", f.index, f.line),
                ));
            }
        }
    }
    Ok(())
}

/// Every frame's capture time lies within the joint samples.
fn check_times(path: &Path, frames: &[FrameRow], joints: &JointTable) -> Result<()> {
    let (first, last) = joints.span();
    for f in frames {
        if !(f.t_s >= first && f.t_s <= last) {
            return Err(SequenceError::file(
                path,
                format!(
                    "frame {} is captured at t = {} s, outside the joint samples [{first}, {last}] s of joints.csv",
                    f.index, f.t_s
                ),
            )
            .at_line(f.line)
            .in_field("t_s"));
        }
    }
    Ok(())
}

/// The ground-truth pose at each frame's capture time.
fn match_groundtruth(path: &Path, frames: &[FrameRow]) -> Result<Vec<Isometry3<f64>>> {
    let poses = tum::read(path)?;
    let mut out = Vec::with_capacity(frames.len());
    let mut j = 0;
    for f in frames {
        while j < poses.len() && poses[j].t < f.t_s - TIME_MATCH_S {
            j += 1;
        }
        match poses.get(j) {
            Some(p) if (p.t - f.t_s).abs() <= TIME_MATCH_S => out.push(p.pose),
            _ => {
                return Err(SequenceError::file(
                    path,
                    format!("no pose at frame {}'s capture time t = {} s (frames.csv line {})", f.index, f.t_s, f.line),
                ));
            }
        }
    }
    Ok(out)
}
