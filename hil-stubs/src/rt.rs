//! Target runtime glue: the semihosting `log` logger, the panic handler, the static frame
//! buffers and the link's FIFO names.

use core::ffi::CStr;

use cortex_m_semihosting::{debug, hprintln};
use static_cell::ConstStaticCell;

use crate::IMAGE_BYTES;
use crate::sys::{HostFile, HostIoError, Mode};

/// Host → firmware FIFO, relative to QEMU's working directory (opened first).
pub const HOST_TO_FIRMWARE: &CStr = c"evorec-h2f.fifo";
/// Firmware → host FIFO (opened second).
pub const FIRMWARE_TO_HOST: &CStr = c"evorec-f2h.fifo";

/// The left and right hue frame buffers (2 × 160×120 bytes, in .bss).
static FRAME_BUFFERS: ConstStaticCell<[[u8; IMAGE_BYTES]; 2]> = ConstStaticCell::new([[0; IMAGE_BYTES]; 2]);

/// The frame buffers; `None` after the first call (they are handed out once).
pub fn frame_buffers() -> Option<&'static mut [[u8; IMAGE_BYTES]; 2]> {
    FRAME_BUFFERS.try_take()
}

/// Opens the link in the order the host expects: host → firmware, then firmware → host.
///
/// # Errors
/// [`HostIoError::Open`] if a FIFO does not exist (no host is attached).
pub fn open_link() -> Result<(HostFile, HostFile), HostIoError> {
    let rx = HostFile::open(HOST_TO_FIRMWARE, Mode::Read)?;
    let tx = HostFile::open(FIRMWARE_TO_HOST, Mode::Write)?;
    Ok((rx, tx))
}

/// Writes `log` records to the host's stdout through semihosting.
struct SemihostingLogger;

impl log::Log for SemihostingLogger {
    fn enabled(&self, metadata: &log::Metadata<'_>) -> bool {
        metadata.level() <= log::max_level()
    }

    fn log(&self, record: &log::Record<'_>) {
        if self.enabled(record.metadata()) {
            hprintln!("[{:5}] {}", record.level(), record.args());
        }
    }

    fn flush(&self) {}
}

static LOGGER: SemihostingLogger = SemihostingLogger;

/// Installs the semihosting logger (idempotent) with `level`.
pub fn init_logger(level: log::LevelFilter) {
    let _ = log::set_logger(&LOGGER);
    log::set_max_level(level);
}

/// Ends the QEMU session with the given success, through semihosting `SYS_EXIT`.
pub fn exit(success: bool) -> ! {
    debug::exit(if success { debug::EXIT_SUCCESS } else { debug::EXIT_FAILURE });
    // Only reached without a debugger attached.
    loop {
        cortex_m::asm::wfi();
    }
}

/// Prints the panic and exits QEMU with failure.
#[cfg(not(feature = "panic-never"))]
#[panic_handler]
fn panic(info: &core::panic::PanicInfo<'_>) -> ! {
    use core::fmt::Write as _;
    // A fresh handle, not `hprintln!`'s shared one: the panic may have happened inside it.
    if let Ok(mut out) = cortex_m_semihosting::hio::hstdout() {
        let _ = writeln!(out, "PANIC: {info}");
    }
    exit(false)
}

/// The `panic-never` build's handler: it calls a function that is defined nowhere, so linking
/// fails while any panic survives optimisation (see `scripts/panic-check.sh`).
#[cfg(feature = "panic-never")]
#[panic_handler]
#[allow(unsafe_code)]
fn panic(_: &core::panic::PanicInfo<'_>) -> ! {
    unsafe extern "Rust" {
        /// Defined nowhere on purpose.
        fn evorec_panic_is_reachable() -> !;
    }
    // SAFETY: never executed — an image that still calls this handler does not link.
    unsafe { evorec_panic_is_reachable() }
}
