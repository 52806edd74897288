//! Layer `experiments`: the tracker on the simulator. One run of a scenario, its tracker set-up
//! and summary ([`experiment`]), the errors against the truth ([`truth`]), the closed loop
//! ([`closed_loop`]) and its experiments ([`servo`]), acquisition statistics ([`acquire`]),
//! the paper's grid ([`paper`]), its seed sweeps ([`paper_seeds`]), the block's own motions
//! ([`target_grid`]) and the parallel runner of the grids ([`grid`]).
//!
//! May use [`sim`](crate::sim) and [`output`](crate::output); never `rig` or `firmware`
//! (they use this layer: `evorec track` sets its tracker up and scores it as a run does,
//! `evorec hil` closes the same loop).

pub mod acquire;
pub mod closed_loop;
pub mod experiment;
pub mod grid;
pub mod paper;
pub mod paper_seeds;
pub mod servo;
pub mod target_grid;
pub mod truth;
