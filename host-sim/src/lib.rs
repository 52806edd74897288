//! # evorec-sim
//!
//! The host simulator of evorec: a PA-10 arm carrying a stereo camera pair ([`arm`],
//! [`motion`]), a renderer of the coloured block ([`render`]), scenario files ([`scenario`]),
//! the simulated camera-controller board ([`sim`]) through which the core's tracker sees the
//! world — the same trait and loop as on the firmware —, runs and their summaries
//! ([`experiment`]), the paper's experiment grid ([`paper`]) and its seed sweeps
//! ([`paper_seeds`]), single-frame rendering
//! ([`frame`]), the same runs with the tracker in the firmware on QEMU ([`hil`]), output
//! files ([`io`]) and plots ([`plot`]); arms from URDF ([`robot`]); recorded stereo sequences
//! (`evorec-seq/1`): the reader ([`sequence`]), tracking them ([`track`]) and writing a
//! scenario as one ([`export`]), and ROS 2 bags read as one ([`bag`]); the host's logger
//! ([`logging`]); unknown starts and occlusions ([`occlusion`]) and the
//! acquisition statistics ([`acquire`]); the block's own paths beyond the paper
//! ([`target_path`]) and their grid ([`target_grid`]); the parallel grid runner ([`grid`]).

pub mod acquire;
pub mod arm;
pub mod bag;
pub mod closed_loop;
pub mod experiment;
pub mod export;
pub mod frame;
pub mod grid;
pub mod hil;
pub mod io;
pub mod logging;
pub mod motion;
pub mod occlusion;
pub mod paper;
pub mod paper_seeds;
pub mod plot;
pub mod render;
pub mod robot;
pub mod rows;
pub mod scenario;
pub mod sequence;
pub mod servo;
pub mod sim;
pub mod target_grid;
pub mod target_path;
pub mod text;
pub mod timing;
pub mod track;
pub mod truth;
