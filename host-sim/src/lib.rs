//! # evorec-sim
//!
//! The host simulator of evorec: a PA-10 arm carrying a stereo camera pair ([`arm`],
//! [`motion`]), a renderer of the coloured block ([`render`]), scenario files ([`scenario`]),
//! the simulated camera-controller board ([`sim`]) through which the core's tracker sees the
//! world — the same trait and loop as on the firmware —, runs and their summaries
//! ([`experiment`]), the paper's experiment grid ([`paper`]), single-frame rendering
//! ([`frame`]), the same runs with the tracker in the firmware on QEMU ([`hil`]), output
//! files ([`io`]) and plots ([`plot`]); unknown starts and occlusions ([`occlusion`]) and the
//! acquisition statistics ([`acquire`]).

pub mod acquire;
pub mod arm;
pub mod experiment;
pub mod frame;
pub mod hil;
pub mod io;
pub mod motion;
pub mod occlusion;
pub mod paper;
pub mod plot;
pub mod render;
pub mod scenario;
pub mod sim;
pub mod timing;
