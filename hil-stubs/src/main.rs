//! The evorec firmware (thumbv7em-none-eabihf, QEMU `mps2-an386`).
//!
//! At start the firmware opens the link FIFOs (see `evorec_firmware::rt`) and serves the host
//! (`evorec_firmware::link_board::serve`): `CONFIG` → tracker, the configured
//! `generations_per_frame` generations (default 2) per `FRAME` through the core's `board::run`,
//! `END` → `DONE` with the stack high-water mark, then exits QEMU with success. Without a host
//! (no FIFOs in QEMU's working directory) it tracks 30 on-board synthetic frames instead, so
//! `cargo run --release` shows it working.
//!
//! Built for the host, this binary only explains how to build the real one.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]
#![deny(unsafe_code)]

#[cfg(target_os = "none")]
mod firmware {
    use cortex_m_rt::entry;
    use evorec_core::board;
    use evorec_firmware::link_board::{self, StackUsage};
    use evorec_firmware::protocol::Setup;
    use evorec_firmware::{FirmwareTracker, rt, selftest, sys};
    use static_cell::StaticCell;

    /// The tracker (a static, built from the host's `CONFIG`). A `StaticCell`, set to `None` at
    /// run time: a `ConstStaticCell::new(None)` would be an initialised static, so its whole
    /// image (the size of a tracker: `None` is a niche value, not zeros) would sit in flash.
    static TRACKER: StaticCell<Option<FirmwareTracker>> = StaticCell::new();

    /// Frames of the demo mode.
    const DEMO_FRAMES: u32 = 30;

    fn report_stack() -> StackUsage {
        let s = sys::stack_usage();
        log::info!("stack high-water mark: {} of {} bytes", s.used_bytes, s.size_bytes);
        s
    }

    #[entry]
    fn main() -> ! {
        rt::init_logger(log::LevelFilter::Info);
        let (Some([left, right]), Some(slot)) = (rt::frame_buffers(), TRACKER.try_init_with(|| None)) else {
            log::error!("static buffers taken twice");
            rt::exit(false)
        };
        match rt::open_link() {
            Ok((rx, tx)) => {
                log::info!("link open");
                rt::exit(link(rx, tx, slot, left, right))
            }
            Err(_) => {
                log::info!("no host link ({:?} missing): demo on on-board synthetic frames", rt::HOST_TO_FIRMWARE);
                rt::exit(demo(slot, left, right))
            }
        }
    }

    /// Serves the host over the link; true on success. Out of line (as [`demo`]), so that
    /// `main`'s frame holds neither path's locals.
    #[inline(never)]
    fn link(
        rx: sys::HostFile,
        tx: sys::HostFile,
        slot: &mut Option<FirmwareTracker>,
        left: &mut [u8],
        right: &mut [u8],
    ) -> bool {
        match link_board::serve(rx, tx, slot, left, right, report_stack) {
            Ok(stats) => {
                log::info!("END: {} frames, {} estimates, {} rejected", stats.frames, stats.published, stats.rejected);
                true
            }
            Err(e) => {
                log::error!("stopped: {e}");
                false
            }
        }
    }

    /// Tracks [`DEMO_FRAMES`] frames of [`selftest::SynthBoard`]; true on success. Out of
    /// line, so that `main`'s frame does not hold the demo's locals on the link path.
    #[inline(never)]
    fn demo(slot: &mut Option<FirmwareTracker>, left: &mut [u8], right: &mut [u8]) -> bool {
        let Some(tracker) = demo_tracker(slot) else { return false };
        let Ok(mut camera) = selftest::SynthBoard::new(DEMO_FRAMES) else { return false };
        match board::run(&mut camera, tracker, left, right, DEMO_FRAMES) {
            Ok(stats) => {
                log::info!("demo: {} frames, {} estimates", stats.frames, stats.published);
                report_stack();
                stats.published == DEMO_FRAMES
            }
            Err(e) => {
                log::error!("demo: {e:?}");
                false
            }
        }
    }

    /// The demo's tracker, built into `slot` (out of line: the configuration and the setup
    /// are gone from the stack before the loop runs).
    #[inline(never)]
    fn demo_tracker(slot: &mut Option<FirmwareTracker>) -> Option<&mut FirmwareTracker> {
        let config = selftest::tracker_config().ok()?;
        let setup = Setup::from_tracker_config(&config, &selftest::START, &selftest::SPREAD).ok()?;
        setup.build_tracker_in(slot).ok()
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    println!(
        "evorec-firmware runs on a Cortex-M4F (thumbv7em-none-eabihf), not on the host.\n\
         Build it:        cd hil-stubs && cargo build --release\n\
         Run it on QEMU:  cd hil-stubs && cargo run --release\n\
         On-target tests: cd hil-stubs && cargo test --release --test on_target\n\
         (needs `rustup target add thumbv7em-none-eabihf` and \
         `apt-get update && apt-get install -y qemu-system-arm`)"
    );
}
