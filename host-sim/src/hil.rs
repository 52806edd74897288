//! `evorec hil`: the same scenario, but the tracker runs in the firmware on QEMU.
//!
//! The simulated board renders each frame (as the cameras' RGB565 pixels) and samples the arm
//! exactly as in `evorec run`;
//! instead of calling the host tracker, the frame and joint sample go over the firmware's
//! semihosting link ([`evorec_firmware::host::HilSession`]) and the firmware's estimate comes
//! back. The firmware runs the core's generic loop on the same numbers, so `trace.csv` and
//! `summary.json` equal those of `evorec run` bit for bit (the workspace test
//! `hil_matches_run` checks it). Nothing is built here.

use std::path::Path;

use anyhow::{Context, Result, bail};
use evorec_core::board::{CameraController, Error as _, ErrorKind};
use evorec_firmware::host::{HilSession, Reply};
use evorec_firmware::protocol::{Frame, Setup};
use evorec_firmware::{FRAME_HEIGHT, FRAME_WIDTH, IMAGE_BYTES};

use crate::experiment::{self, INITIAL_SPREAD, RunOutput, Summary};
use crate::scenario::Scenario;
use crate::sim::{SimBoard, World};

/// Runs `s` with the tracker in the firmware at `firmware` (an ELF), QEMU's working files in
/// `workdir`. `on_frame` is called after every frame.
///
/// # Errors
/// A scenario not at the firmware's frame size, a missing QEMU or firmware (the message says
/// how to install or build it), or a link failure.
pub fn run(s: &Scenario, firmware: &Path, workdir: &Path, mut on_frame: impl FnMut()) -> Result<RunOutput> {
    if (s.camera.width, s.camera.height) != (FRAME_WIDTH, FRAME_HEIGHT) {
        bail!(
            "the firmware takes {FRAME_WIDTH}x{FRAME_HEIGHT} frames but this scenario renders {}x{}; \
             use a scenario at that size (e.g. scenarios/hil_motion_a_ff.toml)",
            s.camera.width,
            s.camera.height
        );
    }
    let world = World::new(s)?;
    let truth0 = world.truth();
    let config = experiment::tracker_config(s)?;
    let setup = Setup::from_tracker_config(&config, experiment::feedforward(s.method), &truth0, &INITIAL_SPREAD)
        .map_err(|e| anyhow::anyhow!("firmware setup: {e:?}"))?;
    let mut session = HilSession::start(firmware, workdir, &setup).map_err(|e| anyhow::anyhow!("{e}"))?;
    let mut board = SimBoard::new(world);
    let (mut left, mut right) = (vec![0u8; IMAGE_BYTES], vec![0u8; IMAGE_BYTES]);
    let mut rejected = 0u32;
    loop {
        let info = match board.next_frame(&mut left, &mut right) {
            Ok(info) => info,
            Err(e) if e.kind() == ErrorKind::EndOfStream => break,
            Err(e) => bail!("simulated board: {e:?}"),
        };
        let joints = board.joint_sample().map_err(|e| anyhow::anyhow!("simulated board: {e:?}"))?;
        let frame = Frame { width: info.width, height: info.height, joints, left: &left, right: &right };
        match session.step(info.sequence, info.capture_time_us, &frame).map_err(|e| anyhow::anyhow!("{e}"))? {
            Reply::Estimate(estimate) => {
                board.publish(&info, &estimate).map_err(|e| anyhow::anyhow!("simulated board: {e:?}"))?;
            }
            Reply::Rejected => rejected += 1,
        }
        on_frame();
    }
    let done = session.finish().map_err(|e| anyhow::anyhow!("{e}")).context("finishing the firmware run")?;
    log::info!("firmware: {:?}, log in {}", done.done, done.log_path.display());
    let rows = board.into_rows();
    let summary = Summary::of(&rows, rejected, s);
    Ok(RunOutput { rows, summary })
}
