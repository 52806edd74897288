//! Layer `firmware`: host tooling for the firmware (`hil-stubs`, on QEMU). The timing and
//! memory budget of one GA generation measured on the board, from the ELF, its disassembly,
//! QEMU, the stack and the flash ([`timing`]), and simulator runs with the tracker in the
//! firmware on QEMU ([`hil`]).
//!
//! May use [`sim`](crate::sim), [`output`](crate::output) and
//! [`experiments`](crate::experiments) (`evorec hil` is the closed loop of
//! [`closed_loop`](crate::experiments::closed_loop) over the link); never `rig`.

pub mod hil;
pub mod timing;
