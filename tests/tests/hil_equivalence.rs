//! Host tracker vs. firmware on QEMU: the same frames and setup give bit-identical estimates.
//!
//! 120 RGB565 frames (160×120 on the M4 profile, 320×240 on the M7; 30 frames/s, 2 bytes per
//! pixel as the cameras deliver them) of the paper's block, rendered with `evorec_core::synth::render_block`, expanded to RGB565 and
//! given sensor noise (the lowest bit of every colour field flipped at random, and one pixel
//! in 16 replaced by a random RGB565 value, so the board's RGB565→hue table is read all over):
//! the block moves in the world while the PA-10 carries
//! the cameras along a sinusoidal joint trajectory (`q̇ ≠ 0`), with feedforward on. One frame
//! is dropped (a 2-period time step) and one has the wrong size (both sides must refuse it).
//! The host runs the core's `board::run` over the recorded frames; the firmware runs the
//! same loop under QEMU, fed through `evorec_firmware::host::HilSession`. Every estimate must
//! match in the bits of ψ and F and in the generation number.
//!
//! The test builds the firmware of the checked-out source first (`cd hil-stubs && cargo build
//! --release`, a no-op when up to date), unless `EVOREC_FIRMWARE_ELF` names an image. A failed
//! build or a missing QEMU fails the test with the message that fixes it; `EVOREC_SKIP_HIL=1`
//! skips the test instead.

use std::path::Path;
use std::time::Instant;

use evorec_core::board::{self, CameraController, ErrorKind, ErrorType, FrameInfo};
use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::ga::SearchSpace;
use evorec_core::image::expand_hue_to_rgb565;
use evorec_core::kinematics::PA10;
use evorec_core::limits::NO_HUE;
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::tracker::{Estimate, JointSample, Tracker, TrackerConfig};
use evorec_core::{quat, synth};
use evorec_firmware::BoardProfile;
use evorec_firmware::host::{HilOptions, HilSession, Reply, build_firmware};
use evorec_firmware::protocol::{Frame, Setup};
use evorec_tests::{Failure, fail};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

const FRAMES: u32 = 120;
const PERIOD_US: u64 = 33_333;
/// This frame is never captured (the next one comes two periods later).
const DROPPED: u32 = 40;
/// This frame has the wrong size; the tracker on both sides refuses it.
const WRONG_SIZE: u32 = 70;

/// One recorded frame pair with its joint sample.
struct Recorded {
    info: FrameInfo,
    left: Vec<u8>,
    right: Vec<u8>,
    joints: JointSample<7>,
}

fn joints_at(t: f32) -> JointSample<7> {
    let q0 = [0.0, 0.5, 0.0, 1.3, 0.0, 0.9, 0.0];
    let amp = [0.03, -0.02, 0.025, 0.03, -0.02, 0.025, 0.04];
    let w = 1.7;
    let (s, c) = (libm_sin(w * t), libm_cos(w * t));
    JointSample {
        q: std::array::from_fn(|i| q0[i] + amp[i] * s),
        qd: std::array::from_fn(|i| amp[i] * w * c),
        time_us: (f64::from(t) * 1e6) as u64,
    }
}

fn libm_sin(x: f32) -> f32 {
    evorec_core::math::sin(x)
}

fn libm_cos(x: f32) -> f32 {
    evorec_core::math::cos(x)
}

/// xorshift32 step.
fn next(x: &mut u32) -> u32 {
    *x ^= *x << 13;
    *x ^= *x >> 17;
    *x ^= *x << 5;
    *x
}

/// Sensor noise on an RGB565 image: each colour field's lowest bit flipped at random, and one
/// pixel in 16 replaced by a random value.
fn sensor_noise(img: &mut [u8], state: &mut u32) {
    for px in img.chunks_exact_mut(2) {
        let r = next(state);
        let v = u16::from_le_bytes([px[0], px[1]]);
        let v = if r.is_multiple_of(16) { (r >> 16) as u16 } else { v ^ (r as u16 & 0x0821) };
        px.copy_from_slice(&v.to_le_bytes());
    }
}

/// The tracker configuration, the setup sent to the firmware and the recorded frames.
/// At `width × height` (160×120 on the M4 profile, 320×240 on the M7), the focal length
/// scaled with the width so that the view is the same.
fn scenario(width: u16, height: u16) -> Result<(TrackerConfig<7>, Setup, Vec<Recorded>), Failure> {
    let f = 200.0 * f32::from(width) / 160.0;
    let (cx, cy) = (f32::from(width) / 2.0, f32::from(height) / 2.0);
    let cam = Pinhole::new_checked(f, f, cx, cy, width, height)?;
    let rig = StereoRig::parallel(cam, 0.1)?;
    let space = SearchSpace::new_checked([-0.25, -0.25, 0.3], [0.25, 0.25, 1.1])?;
    let ft_rot = quat::from_angle_axis(0.08, &Vector3::new(1.0, 0.2, 0.0))?;
    let flange_to_camera = Isometry3::from_parts(Translation3::new(0.0, 0.06, 0.1), ft_rot);
    let config = TrackerConfig::pa10(rig, Block::PAPER, flange_to_camera, space).with_seed(2024);

    // The block's pose in the cameras' frame at t = 0: 0.65 m ahead, a corner turned towards
    // the cameras; from it, its pose in the world.
    let start_rot = quat::from_angle_axis(0.7, &Vector3::new(0.4, 1.0, 0.2))?;
    let block_in_cam0 = Isometry3::from_parts(Translation3::new(-0.04, 0.01, 0.65), start_rot);
    let world_from_cam = |q: &[f32; 7]| PA10.forward(q) * flange_to_camera;
    let world_from_block0 = world_from_cam(&joints_at(0.0).q) * block_in_cam0;

    let n = usize::from(width) * usize::from(height);
    let mut noise = 0x2545_F491u32;
    let mut frames = Vec::new();
    for k in 0..FRAMES {
        if k == DROPPED {
            continue;
        }
        let t = k as f32 * (PERIOD_US as f32 * 1e-6);
        let joints = joints_at(t);
        // The block slides and turns slowly in the world.
        let drift = Isometry3::from_parts(
            Translation3::new(0.03 * libm_sin(1.1 * t), 0.02 * libm_sin(0.7 * t), 0.0),
            UnitQuaternion::from_scaled_axis(Vector3::new(0.0, 0.0, 0.15 * t)),
        );
        let block_in_cam = world_from_cam(&joints.q).inverse() * world_from_block0 * drift;
        let (w, h) = if k == WRONG_SIZE { (80, 60) } else { (width, height) };
        let (mut left, mut right) = (vec![NO_HUE; 2 * n], vec![NO_HUE; 2 * n]);
        if k != WRONG_SIZE {
            synth::render_block(&Block::PAPER, &rig.right, &block_in_cam, &mut right)?;
            synth::render_block(&Block::PAPER, &rig.left, &(rig.left_from_right * block_in_cam), &mut left)?;
            for img in [&mut left, &mut right] {
                expand_hue_to_rgb565(img, n)?;
                sensor_noise(img, &mut noise);
            }
        } else {
            left.truncate(2 * usize::from(w) * usize::from(h));
            right.truncate(2 * usize::from(w) * usize::from(h));
        }
        let info = FrameInfo { sequence: k, capture_time_us: u64::from(k) * PERIOD_US, width: w, height: h };
        frames.push(Recorded { info, left, right, joints });
    }

    let initial = Psi::from_isometry(&block_in_cam0);
    let setup = Setup::from_tracker_config(&config, &initial, &[0.01, 0.01, 0.01, 0.02, 0.02, 0.02])?;
    Ok((config, setup, frames))
}

/// Replays recorded frames to the core's loop on the host and keeps what it publishes.
struct ReplayBoard<'a> {
    frames: std::slice::Iter<'a, Recorded>,
    current: Option<&'a Recorded>,
    published: Vec<(u32, Estimate)>,
}

impl ErrorType for ReplayBoard<'_> {
    type Error = ErrorKind;
}

impl CameraController<7> for ReplayBoard<'_> {
    type Format = evorec_core::image::Rgb565;
    fn next_frame(&mut self, left: &mut [u8], right: &mut [u8]) -> Result<FrameInfo, ErrorKind> {
        let f = self.frames.next().ok_or(ErrorKind::EndOfStream)?;
        left.get_mut(..f.left.len()).ok_or(ErrorKind::Other)?.copy_from_slice(&f.left);
        right.get_mut(..f.right.len()).ok_or(ErrorKind::Other)?.copy_from_slice(&f.right);
        self.current = Some(f);
        Ok(f.info)
    }

    fn joint_sample(&mut self) -> Result<JointSample<7>, ErrorKind> {
        self.current.map(|f| f.joints).ok_or(ErrorKind::Other)
    }

    fn publish(&mut self, frame: &FrameInfo, estimate: &Estimate) -> Result<(), ErrorKind> {
        self.published.push((frame.sequence, *estimate));
        Ok(())
    }
}

/// The estimate bits compared: ψ, F, F per camera, generation, status.
fn bits(e: &Estimate) -> ([u32; 6], u32, [u32; 2], u32, u8) {
    (e.psi.0.map(f32::to_bits), e.fitness.to_bits(), e.camera_fitness.map(f32::to_bits), e.generation, e.status.code())
}

#[test]
fn firmware_estimates_are_bit_identical_to_the_host() -> Result<(), Failure> {
    if evorec_tests::hil_skipped("hil_equivalence") {
        return Ok(());
    }
    equivalence(&build_firmware(BoardProfile::M4)?, BoardProfile::M4)
}

/// The Cortex-M7 profile (QEMU `mps2-an500`, 320×240): its image is built here with
/// `cd hil-stubs && CARGO_TARGET_DIR=../target/m7 cargo build --release --features m7`
/// (a no-op when up to date), or taken from `EVOREC_M7_FIRMWARE_ELF`.
#[test]
fn m7_firmware_estimates_are_bit_identical_to_the_host() -> Result<(), Failure> {
    if evorec_tests::hil_skipped("hil_equivalence (M7)") {
        return Ok(());
    }
    let elf = match std::env::var_os("EVOREC_M7_FIRMWARE_ELF") {
        Some(p) => std::path::PathBuf::from(p),
        None => build_firmware(BoardProfile::M7)?,
    };
    equivalence(&elf, BoardProfile::M7)
}

/// Host loop against the firmware `elf` of `profile` on the recorded frames at the profile's
/// frame size.
fn equivalence(elf: &Path, profile: BoardProfile) -> Result<(), Failure> {
    let (config, setup, frames) = scenario(profile.frame_width, profile.frame_height)?;
    if setup.tracker_config()? != config {
        return Err(fail("Setup does not reproduce the tracker configuration"));
    }

    // Host reference: the core's loop over the recorded frames.
    let t_host = Instant::now();
    let mut host: Tracker = setup.build_tracker()?;
    let image_bytes = 2 * usize::from(profile.frame_width) * usize::from(profile.frame_height);
    let (mut lb, mut rb) = (vec![0u8; image_bytes], vec![0u8; image_bytes]);
    let mut replay = ReplayBoard { frames: frames.iter(), current: None, published: Vec::new() };
    let stats = board::run(&mut replay, &mut host, &mut lb, &mut rb, u32::MAX)
        .map_err(|e| fail(format!("host loop: {e:?}")))?;
    let host_time = t_host.elapsed();
    if stats.rejected != 1 || stats.published as usize != frames.len() - 1 {
        return Err(fail(format!("host loop: unexpected counts {stats:?}")));
    }

    // The firmware under QEMU.
    let workdir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("hil_equivalence_{}", profile.name));
    let t_hil = Instant::now();
    let options = HilOptions { profile, ..HilOptions::default() };
    let mut hil = HilSession::start_with(elf, &workdir, &setup, &options)?;
    let mut fw: Vec<(u32, Estimate)> = Vec::new();
    let mut fw_rejected = Vec::new();
    for f in &frames {
        let frame =
            Frame { width: f.info.width, height: f.info.height, joints: f.joints, left: &f.left, right: &f.right };
        match hil.step(f.info.sequence, f.info.capture_time_us, &frame)? {
            Reply::Estimate(e) => fw.push((f.info.sequence, e)),
            Reply::Rejected => fw_rejected.push(f.info.sequence),
            Reply::Lost => panic!("frame {} lost without fault injection", f.info.sequence),
        }
    }
    let summary = hil.finish()?;
    let hil_time = t_hil.elapsed();

    println!(
        "hil_equivalence ({}, {}x{}): {} frames; host loop {:.3} s, firmware on QEMU {:.3} s ({:.1} ms/frame incl. link)",
        profile.name,
        profile.frame_width,
        profile.frame_height,
        frames.len(),
        host_time.as_secs_f64(),
        hil_time.as_secs_f64(),
        hil_time.as_secs_f64() * 1e3 / frames.len() as f64
    );
    println!(
        "firmware DONE: {} frames, {} estimates, {} rejected; stack high-water mark {} of {} bytes (log: {})",
        summary.done.frames,
        summary.done.published,
        summary.done.rejected,
        summary.done.stack_used_bytes,
        summary.done.stack_size_bytes,
        summary.log_path.display()
    );
    if let Some((_, last)) = fw.last() {
        println!("last estimate: ψ = {:?}, F = {}", last.psi.0, last.fitness);
    }

    // The painted stack must never have been used up (an overflow would run into .bss).
    let headroom = summary.done.stack_size_bytes.saturating_sub(summary.done.stack_used_bytes);
    assert!(headroom >= 4096, "stack headroom only {headroom} bytes: {:?}", summary.done);
    assert_eq!(fw_rejected, [WRONG_SIZE], "the firmware must refuse exactly the wrong-size frame");
    assert_eq!(fw.len(), replay.published.len(), "estimate counts differ");
    assert_eq!(
        (summary.done.frames, summary.done.published, summary.done.rejected),
        (stats.frames, stats.published, stats.rejected)
    );
    let mut first_mismatch = None;
    for ((seq_fw, e_fw), (seq_host, e_host)) in fw.iter().zip(replay.published.iter()) {
        if seq_fw != seq_host || bits(e_fw) != bits(e_host) {
            first_mismatch.get_or_insert((*seq_fw, *e_fw, *seq_host, *e_host));
        }
    }
    assert!(first_mismatch.is_none(), "first differing estimate (firmware, host): {first_mismatch:?}");
    // Sanity: the tracker actually tracked (so the comparison is not of degenerate output).
    let good = fw.iter().filter(|(_, e)| e.fitness > 0.5).count();
    println!("{good} of {} estimates have F > 0.5", fw.len());
    assert!(good * 4 > fw.len(), "only {good} of {} estimates have F > 0.5", fw.len());
    Ok(())
}
