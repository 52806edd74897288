//! Layer `sim`: the simulated world. The PA-10 arm ([`arm`]) and the scripted motions of the
//! flange and the block ([`motion`], [`target_path`]), the renderer of the coloured block
//! ([`render`]), unknown starts and occluders ([`occlusion`]), scenario files ([`scenario`])
//! and the simulated camera-controller board that puts them together ([`board`]), through which
//! the core's tracker sees the world.
//!
//! Uses no other layer of this crate (only `evorec-core` and external crates): every other
//! layer may use it.

pub mod arm;
pub mod board;
pub mod motion;
pub mod occlusion;
pub mod render;
pub mod scenario;
pub mod target_path;
