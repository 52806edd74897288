//! Overload under QEMU: a camera that delivers frames faster than the firmware works them off.
//!
//! The camera is modelled by its schedule, not by a clock: whenever the firmware answers, the
//! frames captured while it was busy are waiting, [`BURSTS`] of them in turn (1, 2, 3, 2, …: on
//! average twice the rate the board works at, up to three frames at a time). The host sends a
//! burst back to back, all but the newest frame flagged `FLAG_NEWER_FOLLOWS` (what a camera
//! interface's "next frame ready" tells a board), and waits for the answer to the newest
//! (`HilSession::step_burst`). The board drops a flagged frame after its header and size,
//! skipping its images in bulk without decoding them (`LinkReader::newest_frames_only`).
//!
//! Checked, the same on every run and on any machine: every answer is to the newest frame of
//! its burst (a board that queued would answer the oldest); the firmware counts exactly the
//! flagged frames as superseded, works on the others and on nothing else, and refuses none
//! (a burst spans at most 0.1 s of capture time, within `max_dt_s`); and the estimates stay on
//! the block although half the frames are never looked at (the feedforward shifts the
//! population over the longer time steps). What skipping costs the board against decoding is
//! counted in reads by the protocol's test
//! `a_superseded_frame_is_skipped_in_a_few_reads_and_the_frame_behind_it_decodes`; without the
//! bulk skip a superseded frame would cross the link in full (32-byte semihosting reads, COBS
//! decoding and CRC of all 76,800 image bytes), about as dear as a generation.
//!
//! Builds the firmware first and needs qemu-system-arm; `EVOREC_SKIP_HIL=1` skips
//! (`cargo test -p evorec-tests --test hil_overload -- --nocapture`).

use evorec_core::board::CameraController;
use evorec_core::pose::Psi;
use evorec_core::tracker::JointSample;
use evorec_firmware::BoardProfile;
use evorec_firmware::host::{HilOptions, HilSession, Reply, build_firmware};
use evorec_firmware::protocol::{DOF, Frame, Setup};
use evorec_firmware::{FRAME_HEIGHT, FRAME_WIDTH, IMAGE_BYTES};
use evorec_sim::experiments::experiment::{self, INITIAL_SPREAD};
use evorec_sim::sim::board::{SimBoard, World};

/// How many frames wait for the firmware each time it answers, in turn.
const BURSTS: [usize; 4] = [1, 2, 3, 2];
/// The largest position error of an answered estimate (m), the 10 mm of a right `tracking`:
/// the block is held throughout (measured: 0.2–3.7 mm, frames 0–120).
const HELD_M: f32 = 0.010;

/// One pre-rendered frame of the simulated scene, with the block's true pose.
struct Recorded {
    sequence: u32,
    capture_time_us: u64,
    joints: JointSample<DOF>,
    left: Vec<u8>,
    right: Vec<u8>,
    truth: Psi,
}

impl Recorded {
    fn message(&self) -> (u32, u64, Frame<'_>) {
        let frame = Frame {
            width: FRAME_WIDTH,
            height: FRAME_HEIGHT,
            joints: self.joints,
            left: &self.left,
            right: &self.right,
        };
        (self.sequence, self.capture_time_us, frame)
    }
}

/// `hil_motion_a_ff` cut to `seconds`: its firmware setup and every frame.
fn scene(seconds: f64) -> (Setup, Vec<Recorded>) {
    let s = evorec_sim::sim::scenario::fixture::hil_motion_a_ff(seconds);
    let world = World::new(&s).expect("world");
    let config = experiment::tracker_config(&s).expect("tracker config");
    let setup = Setup::from_tracker_config(&config, &world.truth(), &INITIAL_SPREAD).expect("firmware setup");
    let mut board = SimBoard::new(world).expect("board");
    let (mut left, mut right) = (vec![0u8; IMAGE_BYTES], vec![0u8; IMAGE_BYTES]);
    let mut frames = Vec::new();
    while let Ok(info) = board.next_frame(&mut left, &mut right) {
        let joints = board.joint_sample().expect("joints");
        frames.push(Recorded {
            sequence: info.sequence,
            capture_time_us: info.capture_time_us,
            joints,
            left: left.clone(),
            right: right.clone(),
            truth: board.world().truth(),
        });
    }
    (setup, frames)
}

#[test]
fn a_camera_faster_than_the_board_gets_its_newest_frames_answered_and_the_rest_counted() {
    if evorec_tests::hil_skipped("hil_overload") {
        return;
    }
    let (setup, frames) = scene(4.0);
    assert!(frames.len() >= 100, "{} frames", frames.len());
    let firmware = build_firmware(BoardProfile::M4).unwrap_or_else(|e| panic!("{e}"));
    let work = std::env::temp_dir().join(format!("evorec-hil-overload-{}", std::process::id()));
    let mut hil =
        HilSession::start_with(&firmware, &work, &setup, &HilOptions::default()).unwrap_or_else(|e| panic!("{e}"));

    let (mut next, mut flagged, mut worked, mut worst) = (0usize, 0u32, 0u32, 0.0f32);
    for size in BURSTS.iter().copied().cycle() {
        let Some(burst) = frames.get(next..next + size) else { break };
        let messages: Vec<(u32, u64, Frame<'_>)> = burst.iter().map(Recorded::message).collect();
        let (answered, reply) = hil.step_burst(&messages).unwrap_or_else(|e| panic!("{e}")).expect("non-empty burst");
        let newest = &burst[size - 1];
        assert_eq!(answered, newest.sequence, "the answer is to the newest frame of the burst");
        let Reply::Estimate(estimate) = reply else { panic!("frame {answered}: {reply:?}") };
        let error = (estimate.psi.translation() - newest.truth.translation()).norm();
        assert!(error <= HELD_M, "frame {answered}: {:.2} mm off", error * 1e3);
        worst = worst.max(error);
        flagged += u32::try_from(size - 1).expect("short burst");
        worked += 1;
        next += size;
    }
    let done = hil.finish().unwrap_or_else(|e| panic!("{e}")).done;
    println!(
        "overload: {next} frames offered in bursts of {BURSTS:?}, {worked} worked on, {flagged} superseded; \
         worst position error {:.2} mm; firmware DONE {done:?}",
        worst * 1e3
    );
    assert_eq!(done.drops.superseded, flagged, "{done:?}");
    assert_eq!((done.frames, done.published, done.rejected), (worked, worked, 0), "{done:?}");
    assert_eq!(done.drops.damaged() + done.drops.sequence + done.drops.unexpected, 0, "{done:?}");
    let _ = std::fs::remove_dir_all(&work);
}
