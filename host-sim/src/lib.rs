//! # evorec-sim
//!
//! The host simulator of evorec: a PA-10 arm carrying a stereo camera pair, a renderer of the
//! coloured block and the simulated camera-controller board through which the core's tracker
//! sees the world — the same trait and loop as on the firmware —, and the commands around it.
//!
//! The crate is split into layers, one folder each, lowest first; a layer uses only the layers
//! it lists, all below it (`tests/tests/module_cycles.rs` checks this):
//!
//! - [`sim`]: the simulated world — the arm and its motions, the block's paths, the renderer,
//!   occlusions, scenario files, the simulated board. Uses no other layer.
//! - [`recording`]: the recorded stereo sequence format `evorec-seq/1` (reader, writer's
//!   pieces, TUM trajectories), arms from URDF. Uses no other layer.
//! - [`output`]: output files (all written through [`output::io`]), plots, the logger and
//!   progress bars, the row-size dispatch, one rendered frame (`evorec render`). Uses `sim`
//!   and `recording`.
//! - [`experiments`]: runs of the tracker on the simulator and their summaries, the errors
//!   against the truth, the closed loop, the paper's grid and seed sweeps, the target grid,
//!   acquisition statistics. Uses `sim` and `output`.
//! - [`rig`]: real-rig input — tracking recorded sequences, ROS 2 bags (read, tracked,
//!   imported, rig files), a scenario exported as a sequence. Uses `sim`, `recording`,
//!   `output` and `experiments`.
//! - [`firmware`]: firmware tooling — timing and memory on QEMU, runs with the tracker in the
//!   firmware. Uses `sim`, `output` and `experiments`.
//!
//! The `evorec` binary's command line (`src/cli/`, one module per group of subcommands) sits
//! on top and may use every layer.

pub mod experiments;
pub mod firmware;
pub mod output;
pub mod recording;
pub mod rig;
pub mod sim;
