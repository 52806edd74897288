//! # evorec-firmware
//!
//! The evorec tracker on a Cortex-M4F camera controller (`thumbv7em-none-eabihf`), run under
//! QEMU (`mps2-an386`) for hardware-in-the-loop tests, and the host side of its link.
//!
//! ```text
//!   host (std)                                     firmware (no_std, QEMU mps2-an386)
//!   HilSession ── CONFIG ─► evorec-h2f.fifo ─► serve(): Setup → Tracker (static)
//!              ── FRAME  ─►                     board::run(LinkBoard, tracker)
//!              ◄─ ESTIMATE ─ evorec-f2h.fifo ◄─   frame → joints → 1 generation → publish
//!              ── END    ─►  ...            ◄─ DONE (counts, stack high-water mark)
//! ```
//!
//! The firmware is glue only: [`link_board::LinkBoard`] implements the core's
//! [`CameraController<7>`](evorec_core::board::CameraController) over the link
//! ([`protocol`]), and the main loop is the core's generic
//! [`evorec_core::board::run`]. The host builds its reference tracker from the same
//! [`protocol::Setup`] ([`setup`]), so host and target trackers are bit-identical and so are
//! their estimates (checked by `tests/tests/hil_equivalence.rs` of the workspace).
//!
//! ## On-board frame size and memory
//! Frames are 2 × 160×120 hue bytes ([`FRAME_WIDTH`] × [`FRAME_HEIGHT`], 37.5 KiB), received
//! straight into two static buffers (no second copy). The tracker (the core's defaults: 7 DOF,
//! storage for [`POPULATION_CAPACITY`](evorec_core::config::POPULATION_CAPACITY) individuals of
//! which `CONFIG` chooses how many are used, [`DEFAULT_POPULATION`](evorec_core::config::DEFAULT_POPULATION) by default,
//! [`DEFAULT_GRID`](evorec_core::config::DEFAULT_GRID) samples per row) lives in a static too. `memory.x` at the workspace root budgets an STM32F4-class
//! part (1 MiB flash, 128 KiB SRAM); the firmware's own budget is flash ≤ 256 KiB and
//! statics + stack ≤ 128 KiB. The stack is painted by cortex-m-rt before `main` and its
//! high-water mark is reported in `DONE` and in the log.
//!
//! Measured (rustc 1.95, release profile: fat LTO, opt-level 3; core defaults):
//!
//! | what                                   | bytes   | how                                   |
//! |----------------------------------------|---------|---------------------------------------|
//! | flash (`.vector_table+.text+.rodata+.data`) | 106 928 | `llvm-size -B` text + data        |
//! | static RAM (`.data+.bss`)              | 41 616  | `llvm-size -B` data + bss             |
//! | stack high-water mark                  | 10 476  | stack painting, 30-frame demo         |
//! | RAM total                              | 52 092  | of 128 KiB                            |
//!
//! The stack peak is the tracker's construction ([`setup`]'s `build_tracker_in` through the
//! core's `Tracker::new_in`, which builds the tracker in its static slot; its frames are
//! 3.9 KB + 2.8 KB); the per-frame loop needs less.
//!
//! ## Commands (run inside `hil-stubs/`, whose `.cargo/config.toml` selects the target)
//! - build the firmware: `cargo build --release`
//!   (→ `target/thumbv7em-none-eabihf/release/evorec-firmware`)
//! - run it on QEMU: `cargo run --release` (without a host on the FIFOs it runs a demo on
//!   on-board synthetic frames)
//! - on-target tests: `cargo test --release --test on_target`
//! - host checks of this crate: from the workspace root,
//!   `cargo test -p evorec-firmware --features host` and
//!   `cargo clippy -p evorec-firmware --all-targets --features host -- -D warnings`
//!
//! ## Features
//! - `host`: the `host` module (`host::HilSession`), the std host side of the QEMU link.
//!
//! ## `unsafe`
//! The crate denies `unsafe_code`; the semihosting calls and the stack scan live in one
//! module (`sys`, target only) with a `SAFETY` comment on every block.
#![no_std]
#![deny(unsafe_code)]
#![deny(missing_docs)]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

#[cfg(any(test, feature = "host"))]
extern crate std;

// The modules that handle link data deny indexing and slicing that can panic (the panic probe,
// scripts/panic-check.sh, checks the compiled result).
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod crc;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod link_board;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod protocol;
pub mod selftest;
#[cfg_attr(not(test), deny(clippy::indexing_slicing))]
pub mod setup;
pub mod timing;

#[cfg(feature = "host")]
pub mod host;

#[cfg(target_os = "none")]
pub mod rt;
#[cfg(target_os = "none")]
#[allow(unsafe_code)]
pub mod sys;
// The timing firmware's TIMER0 driver and stack re-painting (src/bin/evorec-timing.rs).
#[cfg(target_os = "none")]
#[allow(unsafe_code)]
pub mod cmsdk_timer;

/// Width of the on-board hue frames (pixels).
pub const FRAME_WIDTH: u16 = 160;
/// Height of the on-board hue frames (pixels).
pub const FRAME_HEIGHT: u16 = 120;
/// Bytes of one on-board hue image (`FRAME_WIDTH · FRAME_HEIGHT`).
pub const IMAGE_BYTES: usize = FRAME_WIDTH as usize * FRAME_HEIGHT as usize;

/// The firmware's tracker: the core's defaults (7 DOF, default population and grid).
pub type FirmwareTracker = evorec_core::Tracker;
