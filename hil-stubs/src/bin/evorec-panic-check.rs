//! The panic probe (thumbv7em-none-eabihf): a firmware image that contains only the two paths
//! that see untrusted data — the link decoder ([`read_message`](evorec_firmware::protocol::read_message), the firmware's path for
//! `FRAME` and the other messages) and one GA generation (`Tracker::step`) — behind
//! `#[inline(never)]` roots, with inputs the optimiser cannot see through.
//!
//! `hil-stubs/scripts/panic-check.sh` builds it twice:
//! - with the feature `panic-never`, whose panic handler calls a symbol that exists nowhere:
//!   the image links only if the optimiser removed every panic from the image (tracker
//!   construction included);
//! - normally, and lists the panic call sites in its disassembly that the call graph reaches
//!   from `decode_root` and `step_root`.
//!
//! It is never run; built for the host it only says what it is for.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]
#![deny(unsafe_code)]

#[cfg(target_os = "none")]
mod probe {
    use core::hint::black_box;

    use cortex_m_rt::entry;
    use evorec_core::image::Rgb565Image;
    use evorec_core::tracker::{Estimate, JointSample, StereoFrame};
    use evorec_firmware::protocol::{LinkReader, ReadError, SliceSource, Truncated, read_message};
    use evorec_firmware::selftest;
    use evorec_firmware::{FRAME_HEIGHT, FRAME_WIDTH, FirmwareTracker, rt};
    use static_cell::ConstStaticCell;

    static TRACKER: ConstStaticCell<Option<FirmwareTracker>> = ConstStaticCell::new(None);
    /// The link bytes the decoder reads (opaque to the optimiser through `black_box`).
    static LINK: [u8; 64] = [0; 64];

    /// Root of the decode path: one message from `bytes` into the frame buffers, read as the
    /// firmware's board reads (a superseded frame is skipped in bulk).
    #[inline(never)]
    fn decode_root(bytes: &[u8], left: &mut [u8], right: &mut [u8]) -> Result<u32, ReadError<Truncated>> {
        let mut rx = LinkReader::newest_frames_only(SliceSource::new(bytes));
        let env = read_message(&mut rx, left, right)?;
        Ok(env.sequence)
    }

    /// Root of the tracking path: one generation on `left`/`right`.
    #[inline(never)]
    fn step_root(
        tracker: &mut FirmwareTracker,
        left: &[u8],
        right: &[u8],
        joints: &JointSample<7>,
        dt: f32,
    ) -> Option<Estimate> {
        let (w, h) = (black_box(FRAME_WIDTH), black_box(FRAME_HEIGHT));
        let frame = StereoFrame {
            left: Rgb565Image::new_checked(left, w, h).ok()?,
            right: Rgb565Image::new_checked(right, w, h).ok()?,
        };
        tracker.step(&frame, joints, dt).ok()
    }

    #[entry]
    fn main() -> ! {
        let (Some([left, right]), Some(slot)) = (rt::frame_buffers(), TRACKER.try_take()) else { rt::exit(false) };
        let Ok(config) = selftest::tracker_config() else { rt::exit(false) };
        *slot = FirmwareTracker::new(black_box(config)).ok();
        let Some(tracker) = slot.as_mut() else { rt::exit(false) };
        let decoded = decode_root(black_box(&LINK[..]), left, right);
        let joints = black_box(JointSample { q: [0.0; 7], qd: [0.0; 7], time_us: 0 });
        let estimate = step_root(tracker, left, right, &joints, black_box(0.033));
        let _ = black_box((decoded, estimate));
        rt::exit(true)
    }
}

#[cfg(not(target_os = "none"))]
fn main() {
    println!("evorec-panic-check is a Cortex-M4 image for the panic analysis: run hil-stubs/scripts/panic-check.sh");
}
