//! A fixed bring-up scenario, computed identically on the host and on the target.
//!
//! The on-target test runs [`run_steps`] on the Cortex-M4 and compares the estimates' bits
//! with the same function run on the host by `build.rs` (which includes this file as a
//! module and writes the bits to `$OUT_DIR/selftest_expected.rs`). The firmware's demo mode
//! (no host link) tracks [`SynthBoard`]'s frames.
//!
//! This file must only use `core`, `evorec_core` and `nalgebra` (absolute paths, no
//! `crate::`), because `build.rs` compiles it outside this crate.

use evorec_core::board::{CameraController, ErrorKind, ErrorType, FrameInfo};
use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::ga::SearchSpace;
use evorec_core::image::{Rgb565Image, expand_hue_to_rgb565};
use evorec_core::kinematics::PA10;
use evorec_core::limits::NO_HUE;
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::quat;
use evorec_core::synth;
use evorec_core::tracker::{Estimate, JointSample, StereoFrame, Tracker, TrackerConfig};
use nalgebra::{Isometry3, Translation3, Vector3};

/// Image width of the scenario (the on-board frame size).
pub const WIDTH: u16 = 160;
/// Image height of the scenario.
pub const HEIGHT: u16 = 120;
/// Pixels of one image.
pub const PIXELS: usize = WIDTH as usize * HEIGHT as usize;
/// Bytes of one RGB565 image (what the cameras deliver, 2 bytes per pixel).
pub const IMAGE_BYTES: usize = 2 * PIXELS;
/// Generations [`run_steps`] runs.
pub const STEPS: usize = 3;
/// Frame period (µs, 30 frames/s).
pub const FRAME_PERIOD_US: u64 = 33_333;

/// The block's true pose in `Σ_CR` for the static frames: 0.5 m ahead, centred between the
/// two cameras and turned 90° about the optical axis, so both cameras see only its −z face
/// (75 × 50 px at 0.4 m), whose inner sample rows then sit at least a pixel inside the painted
/// area even at 160×120 — the model at this pose scores exactly 1.
pub const TRUTH: Psi = Psi::new([-0.052, 0.003, 0.5], [0.0, 0.0, core::f32::consts::FRAC_1_SQRT_2]);

/// The pose the population starts around (a few mm and a little rotation off the truth).
pub const START: Psi = Psi::new([-0.046, 0.008, 0.51], [0.01, -0.01, 0.69]);

/// Spread of the initial population per gene.
pub const SPREAD: [f32; 6] = [0.02, 0.02, 0.02, 0.03, 0.03, 0.03];

/// What failed while setting the scenario up (the numbers are fixed, so any of these is a bug
/// or a changed core).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Failure {
    /// Camera, rig, search space or quaternion construction.
    Geometry,
    /// `Tracker::new` or `reset_around`.
    Tracker,
    /// Rendering or wrapping an image.
    Image,
    /// A `Tracker::step` was refused.
    Step,
}

/// The estimate of one generation as raw bits (for exact comparison).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EstimateBits {
    /// `ψ` as `f32::to_bits`.
    pub psi: [u32; 6],
    /// `F` as `f32::to_bits`.
    pub fitness: u32,
    /// Generation number.
    pub generation: u32,
}

impl EstimateBits {
    /// The bits of an estimate.
    pub fn of(e: &Estimate) -> Self {
        Self { psi: e.psi.0.map(f32::to_bits), fitness: e.fitness.to_bits(), generation: e.generation }
    }
}

/// The stereo rig: 160×120, f = 200 px, baseline 0.1 m.
///
/// # Errors
/// [`Failure::Geometry`].
pub fn rig() -> Result<StereoRig, Failure> {
    let cam = Pinhole::new_checked(200.0, 200.0, 80.0, 60.0, WIDTH, HEIGHT).map_err(|_| Failure::Geometry)?;
    StereoRig::parallel(cam, 0.1).map_err(|_| Failure::Geometry)
}

/// The tracker configuration: PA-10, paper block, a tilted camera on the flange, seed 7.
///
/// # Errors
/// [`Failure::Geometry`].
pub fn tracker_config() -> Result<TrackerConfig<7>, Failure> {
    let space = SearchSpace::new_checked([-0.2, -0.2, 0.4], [0.2, 0.2, 1.0]).map_err(|_| Failure::Geometry)?;
    let rot = quat::from_angle_axis(0.1, &Vector3::new(0.3, 0.0, 1.0)).map_err(|_| Failure::Geometry)?;
    let flange_to_camera = Isometry3::from_parts(Translation3::new(0.0, 0.06, 0.1), rot);
    Ok(TrackerConfig::pa10(rig()?, Block::PAPER, flange_to_camera, space).with_seed(7))
}

/// Joint sample `k` (frame `k`): a slow sinusoid about a bent PA-10 pose, `q̇ ≠ 0`.
pub fn joints(k: u32) -> JointSample<7> {
    let t = k as f32 * (FRAME_PERIOD_US as f32 * 1e-6);
    let q0 = [0.1, 0.4, -0.1, 1.2, 0.05, 0.6, 0.0];
    let amp = [0.05, -0.04, 0.03, 0.05, -0.03, 0.04, 0.06];
    let w = 2.0;
    let (s, c) = evorec_core::math::sin_cos(w * t);
    JointSample {
        q: core::array::from_fn(|i| q0[i] + amp[i] * s),
        qd: core::array::from_fn(|i| amp[i] * w * c),
        time_us: u64::from(k) * FRAME_PERIOD_US,
    }
}

/// Renders the block at `psi` (in `Σ_CR`) into both RGB565 images (grey background): the
/// core's hue rasterizer into the first [`PIXELS`] bytes, then expanded in place to the
/// RGB565 value of each hue ([`expand_hue_to_rgb565`]).
///
/// # Errors
/// [`Failure::Image`] if a buffer is smaller than [`IMAGE_BYTES`] or `psi` is invalid.
pub fn render(rig: &StereoRig, psi: &Psi, left: &mut [u8], right: &mut [u8]) -> Result<(), Failure> {
    let iso = psi.try_to_isometry().map_err(|_| Failure::Image)?;
    for (img, cam, pose) in [(right, &rig.right, iso), (left, &rig.left, rig.left_from_right * iso)] {
        img.get_mut(..PIXELS).ok_or(Failure::Image)?.fill(NO_HUE);
        synth::render_block(&Block::PAPER, cam, &pose, img).map_err(|_| Failure::Image)?;
        expand_hue_to_rgb565(img, PIXELS).map_err(|_| Failure::Image)?;
    }
    Ok(())
}

/// Builds the scenario's tracker (reset around [`START`]), renders [`TRUTH`] and runs
/// [`STEPS`] generations with motion feedforward (the default tuning's), [`joints`]`(k)`, the
/// first with `dt = 0`, the others one frame period apart.
///
/// # Errors
/// A [`Failure`] (never for the fixed numbers unless the core changed).
pub fn run_steps(left: &mut [u8], right: &mut [u8]) -> Result<[EstimateBits; STEPS], Failure> {
    let rig = rig()?;
    let mut tracker: Tracker = Tracker::new(tracker_config()?).map_err(|_| Failure::Tracker)?;
    tracker.reset_around(&START, &SPREAD).map_err(|_| Failure::Tracker)?;
    render(&rig, &TRUTH, left, right)?;
    let frame = StereoFrame {
        left: Rgb565Image::new_checked(&*left, WIDTH, HEIGHT).map_err(|_| Failure::Image)?,
        right: Rgb565Image::new_checked(&*right, WIDTH, HEIGHT).map_err(|_| Failure::Image)?,
    };
    let mut out = [EstimateBits { psi: [0; 6], fitness: 0, generation: 0 }; STEPS];
    for (k, slot) in out.iter_mut().enumerate() {
        let dt = if k == 0 { 0.0 } else { FRAME_PERIOD_US as f32 * 1e-6 };
        let e = tracker.step(&frame, &joints(k as u32), dt).map_err(|_| Failure::Step)?;
        *slot = EstimateBits::of(&e);
    }
    Ok(out)
}

/// An on-board synthetic camera for the firmware's demo mode: the block held still in the
/// world while the arm moves the cameras along [`joints`], rendered with
/// [`synth::render_block`]; ends after `frames` frames.
#[derive(Debug, Clone)]
pub struct SynthBoard {
    rig: StereoRig,
    world_from_block: Isometry3<f32>,
    flange_to_camera: Isometry3<f32>,
    next: u32,
    frames: u32,
}

impl SynthBoard {
    /// A board that places the block at [`TRUTH`] in the cameras' frame at `joints(0)`.
    ///
    /// # Errors
    /// [`Failure::Geometry`].
    pub fn new(frames: u32) -> Result<Self, Failure> {
        let config = tracker_config()?;
        let cam0 = PA10.forward(&joints(0).q) * config.flange_to_camera;
        let truth = TRUTH.try_to_isometry().map_err(|_| Failure::Geometry)?;
        Ok(Self {
            rig: config.rig,
            world_from_block: cam0 * truth,
            flange_to_camera: config.flange_to_camera,
            next: 0,
            frames,
        })
    }

    /// The block's true pose in `Σ_CR` at frame `k`.
    pub fn truth(&self, k: u32) -> Psi {
        let cam = PA10.forward(&joints(k).q) * self.flange_to_camera;
        Psi::from_isometry(&(cam.inverse() * self.world_from_block))
    }
}

impl ErrorType for SynthBoard {
    type Error = ErrorKind;
}

impl CameraController<7> for SynthBoard {
    type Format = evorec_core::image::Rgb565;
    fn next_frame(&mut self, left: &mut [u8], right: &mut [u8]) -> Result<FrameInfo, ErrorKind> {
        if self.next >= self.frames {
            return Err(ErrorKind::EndOfStream);
        }
        render(&self.rig, &self.truth(self.next), left, right).map_err(|_| ErrorKind::Other)?;
        let info =
            FrameInfo { sequence: self.next, capture_time_us: joints(self.next).time_us, width: WIDTH, height: HEIGHT };
        self.next += 1;
        Ok(info)
    }

    fn joint_sample(&mut self) -> Result<JointSample<7>, ErrorKind> {
        Ok(joints(self.next.saturating_sub(1)))
    }

    fn publish(&mut self, frame: &FrameInfo, estimate: &Estimate) -> Result<(), ErrorKind> {
        let truth = self.truth(frame.sequence);
        let err_mm = (estimate.psi.translation() - truth.translation()).norm() * 1000.0;
        // Printed in fixed point: formatting an f32 takes 2 KB of stack on the board.
        let f_milli = (estimate.fitness * 1000.0) as u32;
        let err_tenths = (err_mm * 10.0) as u32;
        log::info!(
            "frame {:3}: F = {}.{:03}, position error {}.{} mm, generation {}",
            frame.sequence,
            f_milli / 1000,
            f_milli % 1000,
            err_tenths / 10,
            err_tenths % 10,
            estimate.generation
        );
        Ok(())
    }
}
