//! `evorec hil`: the same scenario, but the tracker runs in the firmware on QEMU.
//!
//! The simulated board renders each frame (as the cameras' RGB565 pixels) and samples the arm
//! exactly as in `evorec run`;
//! instead of calling the host tracker, the frame and joint sample go over the firmware's
//! semihosting link ([`evorec_firmware::host::HilSession`]) and the firmware's estimate comes
//! back. The firmware runs the core's generic loop on the same numbers, so `trace.csv` and
//! `summary.json` equal those of `evorec run` bit for bit (the workspace test
//! `hil_matches_run` checks it). A scenario with `[servo]` runs the closed loop
//! ([`run_closed_loop`]): the servo acts on the firmware's estimates, and the run equals the
//! host's closed loop bit for bit (the workspace test `hil_servo`). Nothing is built here.

use std::path::Path;

use anyhow::{Context, Result, bail};
use evorec_core::board::{CameraController, Error as _, ErrorKind};
use evorec_core::pose::Psi;
use evorec_core::tracker::Feedforward;
use evorec_firmware::faults::FaultConfig;
use evorec_firmware::host::{HilOptions, HilSession, Reply};
use evorec_firmware::protocol::{DOF, Frame, LinkFormat, Setup};
use evorec_firmware::{FRAME_HEIGHT, FRAME_WIDTH, IMAGE_BYTES};

use crate::experiments::closed_loop::{ClosedLoopOutput, LoopOptions, ServoBoard};
use crate::experiments::experiment::{self, INITIAL_SPREAD, RunOutput, Summary};
use crate::sim::board::{SimBoard, World};
use crate::sim::scenario::Scenario;

/// Runs `s` with the tracker in the firmware at `firmware` (an ELF), QEMU's working files in
/// `workdir`. `on_frame` is called after every frame.
///
/// # Errors
/// A scenario not at the firmware's frame size, a missing QEMU or firmware (the message says
/// how to install or build it), or a link failure.
pub fn run(s: &Scenario, firmware: &Path, workdir: &Path, on_frame: impl FnMut()) -> Result<RunOutput> {
    Ok(run_with_faults(s, firmware, workdir, None, on_frame)?.0)
}

/// What the link did in a run (`evorec hil --faults`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LinkReport {
    /// The firmware's `DONE` (its loop counts and what it dropped, by reason).
    pub done: evorec_firmware::protocol::Done,
    /// The host's session summary: replies dropped, frames lost, faults injected.
    pub host_drops: evorec_firmware::protocol::DropCounts,
    /// Frames without a valid answer in time.
    pub lost: u32,
    /// Faults injected host → firmware.
    pub faults_sent: evorec_firmware::faults::FaultCounts,
    /// Faults injected firmware → host.
    pub faults_received: evorec_firmware::faults::FaultCounts,
}

impl LinkReport {
    /// One paragraph for the terminal.
    pub fn describe(&self) -> String {
        let d = &self.done;
        format!(
            "link: faults injected {} of {} messages to the firmware, {} of {} replies; firmware: {} frames, {} \
             estimates, {} refused, dropped {:?}; host: {} frames lost, dropped replies {:?}",
            self.faults_sent.total(),
            self.faults_sent.messages,
            self.faults_received.total(),
            self.faults_received.messages,
            d.frames,
            d.published,
            d.rejected,
            d.drops,
            self.lost,
            self.host_drops
        )
    }

    /// The report as JSON.
    pub fn to_json(&self) -> String {
        let f = |c: &evorec_firmware::faults::FaultCounts| {
            format!(
                "{{\"messages\": {}, \"flip\": {}, \"drop\": {}, \"duplicate\": {}, \"truncate\": {}, \"delay\": {}}}",
                c.messages, c.flip, c.drop, c.duplicate, c.truncate, c.delay
            )
        };
        let dr = |c: &evorec_firmware::protocol::DropCounts| {
            format!(
                "{{\"framing\": {}, \"header\": {}, \"length\": {}, \"crc\": {}, \"value\": {}, \"sequence\": {}, \"unexpected\": {}, \"superseded\": {}}}",
                c.framing, c.header, c.length, c.crc, c.value, c.sequence, c.unexpected, c.superseded
            )
        };
        let d = &self.done;
        format!(
            "{{\n  \"firmware\": {{\"frames\": {}, \"published\": {}, \"rejected\": {}, \"dropped\": {}}},\n  \"host\": {{\"lost\": {}, \"dropped\": {}}},\n  \"faults_to_firmware\": {},\n  \"faults_to_host\": {}\n}}\n",
            d.frames,
            d.published,
            d.rejected,
            dr(&d.drops),
            self.lost,
            dr(&self.host_drops),
            f(&self.faults_sent),
            f(&self.faults_received)
        )
    }
}

/// [`run`] with link fault injection at `faults`' rate into both directions (`None`: a clean
/// link); also returns what the link did.
///
/// # Errors
/// As [`run`].
pub fn run_with_faults(
    s: &Scenario,
    firmware: &Path,
    workdir: &Path,
    faults: Option<FaultConfig>,
    on_frame: impl FnMut(),
) -> Result<(RunOutput, LinkReport)> {
    run_with_options(s, firmware, workdir, &options_with_faults(faults), on_frame)
}

/// The session options of `evorec hil --faults`: `faults` (`None`: a clean link) into both
/// directions, each with its own random stream.
pub fn options_with_faults(faults: Option<FaultConfig>) -> HilOptions {
    HilOptions {
        faults_to_firmware: faults,
        faults_to_host: faults.map(|c| FaultConfig { seed: c.seed.wrapping_add(1), ..c }),
        ..Default::default()
    }
}

/// [`run`] with the session's `options` (fault injection per direction, timeouts); also
/// returns what the link did. A frame without a valid answer ([`Reply::Lost`]) is counted as
/// refused, as the board publishes nothing for it.
///
/// # Errors
/// As [`run`].
pub fn run_with_options(
    s: &Scenario,
    firmware: &Path,
    workdir: &Path,
    options: &HilOptions,
    on_frame: impl FnMut(),
) -> Result<(RunOutput, LinkReport)> {
    let mut board = SimBoard::new(World::new(s)?)?;
    let mut session = start_session(s, &board.start_pose(), s.tuning().feedforward, firmware, workdir, options)?;
    let rejected = drive(&mut session, &mut board, on_frame)?;
    let link = finish(session)?;
    let rows = board.into_rows();
    let summary = Summary::of(&rows, rejected, s);
    Ok((RunOutput { rows, summary }, link))
}

/// The closed loop of a scenario with `[servo]` (`evorec hil` on such a scenario) with the
/// tracker in the firmware: the same [`ServoBoard`] as [`crate::experiments::closed_loop::run`], but each frame
/// goes over the link and the servo acts on the firmware's estimate of it, so the arm's motion
/// depends on what the firmware computed. Host and firmware being bit-identical, the output
/// equals [`crate::experiments::closed_loop::run`]'s on a clean link ([`crate::experiments::closed_loop::compare`]).
///
/// # Errors
/// As [`run`], and no `[servo]` section.
pub fn run_closed_loop(
    s: &Scenario,
    opts: &LoopOptions,
    firmware: &Path,
    workdir: &Path,
    options: &HilOptions,
    on_frame: impl FnMut(),
) -> Result<(ClosedLoopOutput, LinkReport)> {
    let mut board = ServoBoard::closed_loop(s, opts)?;
    let mut session = start_session(s, &board.start_pose(), board.feedforward(), firmware, workdir, options)?;
    let rejected = drive(&mut session, &mut board, on_frame)?;
    let link = finish(session)?;
    Ok((board.finish(rejected), link))
}

/// Starts the firmware on QEMU with the tracker of `s`, its population around `start`.
fn start_session(
    s: &Scenario,
    start: &Psi,
    feedforward: Feedforward,
    firmware: &Path,
    workdir: &Path,
    options: &HilOptions,
) -> Result<HilSession> {
    if (s.camera.width, s.camera.height) != (FRAME_WIDTH, FRAME_HEIGHT) {
        bail!(
            "the firmware takes {FRAME_WIDTH}x{FRAME_HEIGHT} frames but this scenario renders {}x{}; \
             use a scenario at that size (e.g. scenarios/hil_motion_a_ff.toml)",
            s.camera.width,
            s.camera.height
        );
    }
    let config = experiment::tracker_config(s)?.with_feedforward(feedforward);
    let setup = Setup::from_tracker_config(&config, start, &INITIAL_SPREAD)
        .map_err(|e| anyhow::anyhow!("firmware setup: {e:?}"))?;
    HilSession::start_with(firmware, workdir, &setup, options).map_err(|e| anyhow::anyhow!("{e}"))
}

/// Streams every frame of `board` with its joint sample to the firmware and publishes the
/// firmware's estimates on the board, in lock-step; returns the frames without an estimate.
fn drive<B>(session: &mut HilSession, board: &mut B, mut on_frame: impl FnMut()) -> Result<u32>
where
    B: CameraController<DOF, Format = LinkFormat>,
{
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
            Reply::Rejected | Reply::Lost => rejected += 1,
        }
        on_frame();
    }
    Ok(rejected)
}

/// Ends the session (`END` → `DONE`) and reports what the link did.
fn finish(session: HilSession) -> Result<LinkReport> {
    let done = session.finish().map_err(|e| anyhow::anyhow!("{e}")).context("finishing the firmware run")?;
    log::info!("firmware: {:?}, log in {}", done.done, done.log_path.display());
    Ok(LinkReport {
        done: done.done,
        host_drops: done.host_drops,
        lost: done.lost,
        faults_sent: done.faults_sent,
        faults_received: done.faults_received,
    })
}
