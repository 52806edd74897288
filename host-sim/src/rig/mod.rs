//! Layer `rig`: input from a real rig. Tracking a recorded sequence ([`track`]), ROS 2 bags
//! read as sequences, tracked directly or imported, and the rig file generated from a bag
//! ([`bag`]), and a simulator scenario written as a recorded sequence ([`export`]).
//!
//! May use [`sim`](crate::sim), [`recording`](crate::recording), [`output`](crate::output)
//! and [`experiments`](crate::experiments) (the tracker's set-up and the errors against the
//! truth); never `firmware`.

pub mod bag;
pub mod export;
pub mod track;
