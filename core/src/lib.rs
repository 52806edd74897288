//! # evorec-core
//!
//! On-line evolutionary 3D pose recognition for hand-eye stereo cameras, after
//! *"On-line Stable Evolutionary Recognition by Quaternion Motion-Feedforward Compensation"*:
//! a genetic algorithm searches the pose `ψ = [t; ε]` of a known coloured block by projecting a
//! 3D surface-strips model into both hue images; the paper runs **one** generation per new
//! frame pair (the "1-step GA"), this crate
//! [`Tuning::generations_per_frame`](tuning::Tuning::generations_per_frame) of them (default
//! 2), so recognition converges over the frame sequence, and the apparent motion caused by the
//! arm carrying the cameras is fed forward from the joint state (`ψ̇ = J_m(q) q̇`).
//!
//! `#![no_std]`, no allocation, no `unsafe`; all storage is sized by const generics.
//!
//! ## Layers
//! - [`math`]: the only path to `sqrt`/`sin`/… (libm), so host and Cortex-M4 agree bit for bit.
//! - [`quat`], [`pose`]: unit quaternions (eq. 1–12) and the 6-parameter pose (eq. 13).
//! - [`camera`]: pinhole cameras and the stereo rig (eq. 26–31).
//! - [`image`]: validated image views in the sensor's pixel format (hue bytes or raw RGB565,
//!   converted to hue only where the sample points hit); [`hue`]: RGB→hue, the hue match table.
//! - [`model`]: the surface-strips block model; [`fitness`]: eq. 34–35; [`edge`]: where a
//!   camera's partly covered pixels put a silhouette, learnt from the disparity.
//! - [`ga`]: the 1-step GA; [`kinematics`]: serial chains (from DH or URDF), the PA-10, Jacobians;
//!   [`feedforward`]: eq. 15–25; [`target_motion`]: the target's own motion (eq. 23's
//!   `J_n` term) and the hand-over of a pose to a later time; [`servo`]: a position-based
//!   visual servo law on the handed-over pose.
//! - [`status`]: searching / tracking / lost; [`acquire`]: the colour-blob pose seed.
//! - [`tracker`]: `generations_per_frame` generations per frame pair (default 2; 1 is the
//!   paper's 1-step GA), up to [`MAX_GENERATIONS_PER_FRAME`](limits::MAX_GENERATIONS_PER_FRAME)
//!   where the frame period allows; [`board`]: the camera-controller trait and the generic loop;
//!   [`synth`]: an exact hue rasterizer for tests and bring-up.
//!
//! ## Work per generation
//! Per individual and camera the fitness walks exactly
//! [`SurfaceStrips::WALKED_PER_CAMERA`](model::SurfaceStrips::WALKED_PER_CAMERA)
//! `= 48·G` sample points, visible or not; a generation evaluates `P` individuals in
//! two cameras and breeds `P − 1` children with a fixed number of random draws each. No loop
//! depends on the data, so the worst case is the typical case. A frame runs
//! [`Tuning::generations_per_frame`](tuning::Tuning::generations_per_frame)
//! such generations after one feedforward shift, and one target-filter update. Fixed numbers
//! of individuals are left unevaluated to pay for a frame's other work: in every generation
//! while not tracking, for the acquisition's stage; while tracking, in a frame's last
//! generation, for the disparity test of [`edge`] on one frame in
//! [`EDGE_PROBE_EVERY`](limits::EDGE_PROBE_EVERY), and as the budget's margin on the others.
//!
//! ## Example
//! ```
//! use evorec_core::{camera::{Pinhole, StereoRig}, ga::SearchSpace, model::Block, pose::Psi,
//!     tracker::{Tracker, TrackerConfig, StereoFrame, JointSample, Feedforward}, image::HueImage,
//!     synth, limits::NO_HUE};
//! use nalgebra::Isometry3;
//!
//! let cam = Pinhole::new_checked(400.0, 400.0, 160.0, 120.0, 320, 240).unwrap();
//! let rig = StereoRig::parallel(cam, 0.1).unwrap();
//! let space = SearchSpace::new_checked([-0.2, -0.2, 0.4], [0.2, 0.2, 1.0]).unwrap();
//! let config = TrackerConfig::pa10(rig, Block::PAPER, Isometry3::identity(), space).with_seed(1).with_feedforward(Feedforward::Off);
//! let mut tracker: Tracker = Tracker::new(config).unwrap();
//!
//! // A synthetic frame pair of the block 0.7 m ahead.
//! let truth = Psi::new([0.0, 0.0, 0.7], [0.0, 0.2, 0.0]);
//! let iso = truth.try_to_isometry().unwrap();
//! let (mut l, mut r) = (vec![NO_HUE; 320 * 240], vec![NO_HUE; 320 * 240]);
//! synth::render_block(&Block::PAPER, &rig.right, &iso, &mut r).unwrap();
//! synth::render_block(&Block::PAPER, &rig.left, &(rig.left_from_right * iso), &mut l).unwrap();
//! let frame = StereoFrame {
//!     left: HueImage::new_checked(&l[..], 320, 240).unwrap(),
//!     right: HueImage::new_checked(&r[..], 320, 240).unwrap(),
//! };
//! let joints = JointSample { q: [0.0; 7], qd: [0.0; 7], time_us: 0 };
//! // Start 17 mm and ~1° away from the truth (the paper starts tracking at a known pose).
//! tracker.reset_around(&Psi::new([0.01, -0.01, 0.71], [0.0, 0.19, 0.0]), &[0.01; 6]).unwrap();
//! let mut est = tracker.step(&frame, &joints, 0.0).unwrap();
//! for _ in 0..150 {
//!     est = tracker.step(&frame, &joints, 0.033).unwrap();
//! }
//! let err = est.psi.translation() - truth.translation();
//! assert!(est.fitness > 0.9);
//! assert!(err.norm() < 0.01);
//! ```
#![no_std]
#![forbid(unsafe_code)]
#![deny(missing_docs)]
#![cfg_attr(not(test), deny(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

#[cfg(test)]
extern crate std;

#[macro_use]
mod error_enum;

// No indexing or slicing that can panic (`clippy::indexing_slicing`) in the modules below that
// carry the lint: `get`, iterators, pattern matching or fixed-size conversions instead. The
// fitness kernel, model, camera and hue modules still index (bounds proven by construction;
// the panic probe, hil-stubs/scripts/panic-check.sh, checks what survives in the firmware).
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod acquire;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod board;
pub mod camera;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod colour;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod edge;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod feedforward;
pub mod fitness;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod ga;
pub mod hue;
pub mod image;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod kinematics;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod limits;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod math;
pub mod model;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod pose;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod quat;
pub mod servo;
pub mod status;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod synth;
pub mod target_motion;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod tracker;
pub mod tuning;

pub use tracker::{Estimate, Feedforward, JointSample, StereoFrame, Tracker, TrackerConfig};
pub use tuning::{ConfigError, Tuning};
