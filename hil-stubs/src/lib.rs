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
//! Frames are 2 × 160×120 RGB565 pixels ([`FRAME_WIDTH`] × [`FRAME_HEIGHT`], 2 bytes each,
//! 75 KiB), what OV7670/OV2640-class sensors deliver, received straight into two static
//! buffers (no second copy). The board computes the hue of the pixels its sample points hit
//! through the core's 64 KiB `RGB565_HUE` table (one more load per point, read-only data in
//! flash); no whole frame is converted. The tracker (the core's defaults: 7 DOF,
//! storage for [`POPULATION_CAPACITY`](evorec_core::limits::POPULATION_CAPACITY) individuals of
//! which `CONFIG` chooses how many are used,
//! [`DEFAULT_POPULATION`](evorec_core::limits::DEFAULT_POPULATION) by default,
//! [`DEFAULT_GRID`](evorec_core::limits::DEFAULT_GRID) samples per row) lives in a static too
//! and is built in place (`Tracker::new_in`: model, hue-match table and population are
//! written where they live, so no tracker-sized temporary is on the stack). `memory.x` at the
//! workspace root budgets an STM32F4-class part (1 MiB flash, 128 KiB SRAM); the firmware's
//! own budget is flash ≤ 256 KiB plus the hue table, and statics + stack ≤ 128 KiB with a
//! stack ≤ 6 KiB. The stack is painted by cortex-m-rt before `main` and its high-water mark
//! is reported in `DONE` and in the log.
//!
//! Measured (rustc 1.95, release profile: fat LTO, opt-level 3; core defaults):
//!
//! | what                                   | bytes   | how                                   |
//! |----------------------------------------|---------|---------------------------------------|
//! | flash (`.vector_table+.text+.rodata+.data`) | 191 188 | `llvm-size -B` text + data        |
//! | of which the RGB565→hue table          | 65 536  | `llvm-nm -S` (`RGB565_HUE`)           |
//! | static RAM (`.data+.bss`)              | 82 408  | `llvm-size -B` data + bss (76 800: frames) |
//! | stack high-water mark                  | 5 316   | stack painting, 30-frame demo (`cargo run --release`) |
//! | RAM total                              | 87 724  | of 128 KiB                            |
//!
//! The stack's deepest path is building the tracker in the demo (`main` → demo →
//! `demo_tracker` → `Setup::build_tracker_in`); a generation (`main` → demo →
//! `Tracker::step_probed`) needs less.
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
pub mod faults;
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

/// A board the firmware is built for: its QEMU machine and its frame size.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BoardProfile {
    /// Short name ("m4", "m7").
    pub name: &'static str,
    /// QEMU `-cpu`.
    pub qemu_cpu: &'static str,
    /// QEMU `-machine`.
    pub qemu_machine: &'static str,
    /// Frame width (pixels).
    pub frame_width: u16,
    /// Frame height (pixels).
    pub frame_height: u16,
}

impl BoardProfile {
    /// The Cortex-M4F camera controller (STM32F4-class, 128 KiB RAM, `memory.x`), 160×120.
    pub const M4: Self =
        Self { name: "m4", qemu_cpu: "cortex-m4", qemu_machine: "mps2-an386", frame_width: 160, frame_height: 120 };
    /// The Cortex-M7 camera controller (STM32H7-class, 512 KiB RAM, `memory.x` with
    /// `__evorec_m7`; feature `m7`), 320×240.
    pub const M7: Self =
        Self { name: "m7", qemu_cpu: "cortex-m7", qemu_machine: "mps2-an500", frame_width: 320, frame_height: 240 };
}

/// The profile this crate is built for (feature `m7` selects [`BoardProfile::M7`]).
pub const PROFILE: BoardProfile = if cfg!(feature = "m7") { BoardProfile::M7 } else { BoardProfile::M4 };

/// Width of the on-board frames (pixels).
pub const FRAME_WIDTH: u16 = PROFILE.frame_width;
/// Height of the on-board frames (pixels).
pub const FRAME_HEIGHT: u16 = PROFILE.frame_height;
/// Bytes of one on-board RGB565 image (`FRAME_WIDTH · FRAME_HEIGHT ·`
/// [`protocol::BYTES_PER_PIXEL`]).
pub const IMAGE_BYTES: usize = FRAME_WIDTH as usize * FRAME_HEIGHT as usize * protocol::BYTES_PER_PIXEL;

/// The firmware's tracker: the core's defaults (7 DOF, default population and grid).
pub type FirmwareTracker = evorec_core::Tracker;
