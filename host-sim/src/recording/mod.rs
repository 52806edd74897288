//! Layer `recording`: the recorded stereo sequence format `evorec-seq/1` ([`sequence`]: the
//! reader, the writer's pieces, TUM trajectories) and what reading one needs: serial arms from
//! URDF ([`robot`]) and the one-line text of the readers' errors ([`text`]).
//!
//! Uses no other layer of this crate. It sits below [`output`](crate::output) because the
//! output files include `estimate.tum`, written with [`sequence::tum`]; the commands that read
//! and write recordings are in [`rig`](crate::rig).

pub mod robot;
pub mod sequence;
pub mod text;
