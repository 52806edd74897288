//! Worst-case timing of one GA generation on the Cortex-M4 (the `evorec-timing` firmware) —
//! the portable half: the phase probe, the test frames, and the report lines the host parses.
//!
//! The timing firmware (`src/bin/evorec-timing.rs`) runs under QEMU with `-icount shift=10`,
//! where every guest instruction advances virtual time by 2¹⁰ ns and the CMSDK TIMER0
//! (25 MHz SYSCLK, 40 ns a tick) counts down on that virtual time, so
//! `instructions = ticks · 40 / 2¹⁰` ([`ticks_to_instructions`]), identically run after run.
//! [`PhaseTimer`] is the core's [`PhaseProbe`] reading such a down-counter at each phase
//! boundary of [`Tracker::step_probed`](evorec_core::tracker::Tracker::step_probed).
//!
//! Frames are made on the board ([`CaseGen`]: the core's `synth` rasterizer, expanded to the
//! RGB565 pixels the cameras deliver, plus a xorshift noise generator), not streamed: the
//! measured window contains nothing but the tracker's code, which reads RGB565 and computes
//! the hue of every sampled pixel through the core's 64 KiB `RGB565_HUE` table, so the hue
//! work is in every count. [`schedule`] lists the kinds of frames of a run: normal frames
//! with the target tracked or at random poses, blank frames, target absent (distractor
//! patches only), target filling the image, pure RGB565 noise (every table entry), target
//! under noise, RGB565 extremes (the table's ends and the pure primaries), and fast arm
//! motion (large feedforward shifts that push individuals into the search-space clamps).
//! Two more kinds force the tracker's status before each generation: the target visible while
//! the tracker searches for it or has lost it (the acquisition's stages run in those
//! generations: scan, solve, refinement, seeded individuals).
//!
//! Every [`GenLine`] carries the status the generation started in (the status decides the
//! work of a generation), so the host can check every status against the budget.
//!
//! Every measured generation is printed as one line ([`GenLine`], `GEN key=value …`), which
//! `evorec timing` (host) parses with [`GenLine::parse`].

use core::fmt;

use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::hue;
use evorec_core::image::expand_hue_to_rgb565;
use evorec_core::kinematics::PA10;
use evorec_core::limits::NO_HUE;
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::status::Status;
use evorec_core::synth;
use evorec_core::tracker::{Feedforward, JointSample, Phase, PhaseProbe};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// `-icount` shift the numbers assume (2^10 ns of virtual time per instruction).
pub const ICOUNT_SHIFT: u32 = 10;
/// Nanoseconds per TIMER0 tick (mps2-an386 SYSCLK = 25 MHz).
pub const NS_PER_TICK: u64 = 40;
/// First line the timing firmware prints (format version).
pub const BANNER: &str = "EVOREC-TIMING v1";
/// Frame period of the timing runs (µs, 30 frames/s).
pub const FRAME_PERIOD_US: u64 = 33_333;

/// Instructions executed in `ticks` TIMER0 ticks under `-icount shift=`[`ICOUNT_SHIFT`].
pub fn ticks_to_instructions(ticks: u64) -> f64 {
    (ticks * NS_PER_TICK) as f64 / f64::from(1u32 << ICOUNT_SHIFT)
}

/// A free-running 32-bit down-counter (TIMER0 on the board, a fake one in tests).
pub trait DownCounter {
    /// The current count.
    fn read(&self) -> u32;
}

/// Ticks spent in each phase of one generation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PhaseTicks {
    /// Feedforward shift of the population ([`Phase::Feedforward`] → [`Phase::Evaluate`]).
    pub feedforward: u32,
    /// Projection + fitness of every individual ([`Phase::Evaluate`] → [`Phase::Breed`]).
    pub evaluate: u32,
    /// Selection, crossover, mutation ([`Phase::Breed`] → [`Phase::Done`]).
    pub breed: u32,
}

/// A [`PhaseProbe`] that reads a [`DownCounter`] when each phase begins.
#[derive(Debug)]
pub struct PhaseTimer<'c, C> {
    clock: &'c C,
    marks: [u32; 4],
    seen: u8,
}

impl<'c, C: DownCounter> PhaseTimer<'c, C> {
    /// A probe on `clock`.
    pub fn new(clock: &'c C) -> Self {
        Self { clock, marks: [0; 4], seen: 0 }
    }

    /// The ticks of each phase, or `None` unless all four marks were seen.
    pub fn phases(&self) -> Option<PhaseTicks> {
        let [ff, ev, br, done] = self.marks;
        // A down-counter: earlier minus later (wrapping, TIMER0 reloads at 0).
        (self.seen == 0b1111).then(|| PhaseTicks {
            feedforward: ff.wrapping_sub(ev),
            evaluate: ev.wrapping_sub(br),
            breed: br.wrapping_sub(done),
        })
    }
}

impl<C: DownCounter> PhaseProbe for PhaseTimer<'_, C> {
    #[inline(always)]
    fn mark(&mut self, phase: Phase) {
        let now = self.clock.read();
        let i = match phase {
            Phase::Feedforward => 0,
            Phase::Evaluate => 1,
            Phase::Breed => 2,
            Phase::Done => 3,
        };
        if let Some(m) = self.marks.get_mut(i) {
            *m = now;
        }
        self.seen |= 1 << i;
    }
}

/// The kinds of test frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CaseKind {
    /// The target on a smooth path, tracked (the normal case).
    Tracking,
    /// The target carried by a conveyor: [`CONVEYOR_SPEED_M_S`] along world y, back and forth
    /// over [`CONVEYOR_TRAVEL_M`], while the arm moves as in [`CaseKind::Tracking`]; a block
    /// long enough for the target filter to converge, so that `ff+target` feeds the target's
    /// velocity forward to every individual (the schedule gives it three blocks in a row).
    Conveyor,
    /// The target at a fresh random pose every frame.
    RandomPose,
    /// Every pixel `NO_HUE`.
    Blank,
    /// No target; patches of hues that match no face.
    Absent,
    /// The target so close that its faces fill the image.
    Filling,
    /// Every pixel the hue of one face.
    UniformHue,
    /// Every pixel a random RGB565 value (any entry of the hue table, matching or not).
    Noise,
    /// The target with a quarter of the pixels replaced by random RGB565 values.
    NoisyTarget,
    /// Every pixel one of [`RGB565_EXTREMES`] at random: the hue table's first and last
    /// entries (black, white: no hue) and the pure primaries (the paper block's face hues).
    Rgb565Extremes,
    /// The target tracked while the arm moves fast (large feedforward shifts, clamping).
    FastArm,
    /// The tracker forced to [`Status::Searching`] before each generation (acquisition
    /// running) on, in turn, the target at a random pose, every pixel one face's hue, and the
    /// target under noise.
    Searching,
    /// The tracker forced to [`Status::Lost`] before each generation (acquisition running)
    /// on, in turn, the target on its path, the target filling the image, and pure noise.
    Lost,
}

impl CaseKind {
    /// Every kind, in schedule order.
    pub const ALL: [CaseKind; 13] = [
        Self::Tracking,
        Self::Conveyor,
        Self::Blank,
        Self::Absent,
        Self::Filling,
        Self::UniformHue,
        Self::Noise,
        Self::NoisyTarget,
        Self::Rgb565Extremes,
        Self::RandomPose,
        Self::Searching,
        Self::Lost,
        Self::FastArm,
    ];

    /// The name printed in [`GenLine`]s.
    pub fn name(self) -> &'static str {
        match self {
            Self::Tracking => "tracking",
            Self::Conveyor => "conveyor",
            Self::RandomPose => "random_pose",
            Self::Blank => "blank",
            Self::Absent => "absent",
            Self::Filling => "filling",
            Self::UniformHue => "uniform_hue",
            Self::Noise => "noise",
            Self::NoisyTarget => "noisy_target",
            Self::Rgb565Extremes => "rgb565_extremes",
            Self::FastArm => "fast_arm",
            Self::Searching => "searching",
            Self::Lost => "lost",
        }
    }

    /// The status the tracker is forced into before generation `k` of this kind (the status
    /// decides the work of a generation): searching and lost for those kinds; for every other
    /// kind tracking and uncertain in turn (a forced `Uncertain` runs the turn probes of a hold
    /// that has gone unconfirmed), so that the work of both is measured on every kind of image.
    pub fn forced_status(self, k: u32) -> Status {
        match self {
            Self::Searching => Status::Searching,
            Self::Lost => Status::Lost,
            _ if k % 2 == 1 => Status::Uncertain,
            _ => Status::Tracking,
        }
    }

    /// The kind printed as `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// Frames of the default configuration's runs (11 of every kind, 33 of the conveyor).
pub const FULL_FRAMES: u32 = 165;
/// Frames of each configuration of the sweep (every kind three times, the conveyor nine).
pub const SWEEP_FRAMES: u32 = 45;

/// Speed of the conveyor of [`CaseKind::Conveyor`] (m/s, along world y).
pub const CONVEYOR_SPEED_M_S: f32 = 0.1;
/// Length the conveyor carries the target back and forth over (m).
pub const CONVEYOR_TRAVEL_M: f32 = 0.12;

/// The blocks of a run in order: every kind once, [`CaseKind::Conveyor`] three times in a row
/// (the target motion model's velocity, once observed, is fed forward in the later blocks).
const SLOTS: [CaseKind; 15] = [
    CaseKind::Tracking,
    CaseKind::Conveyor,
    CaseKind::Conveyor,
    CaseKind::Conveyor,
    CaseKind::Blank,
    CaseKind::Absent,
    CaseKind::Filling,
    CaseKind::UniformHue,
    CaseKind::Noise,
    CaseKind::NoisyTarget,
    CaseKind::Rgb565Extremes,
    CaseKind::RandomPose,
    CaseKind::Searching,
    CaseKind::Lost,
    CaseKind::FastArm,
];

/// The pixels of [`CaseKind::Rgb565Extremes`]: black and white (the hue table's first and last
/// entries, no hue) and pure red, green and blue (every colour field at its extreme).
pub const RGB565_EXTREMES: [u16; 5] = [0x0000, 0xFFFF, 0xF800, 0x07E0, 0x001F];

/// The kind of frame `k` of a run of `frames` frames: blocks of consecutive frames of one
/// kind (so the tracker's state evolves as in operation: it loses the target on blank
/// frames and re-acquires it), every kind in equal share but the conveyor (three shares in a row),
/// tracking first.
pub fn schedule(k: u32, frames: u32) -> CaseKind {
    let slots = SLOTS.len() as u32;
    let block = frames.div_ceil(slots).max(1);
    let i = (k / block).min(slots - 1);
    SLOTS.get(i as usize).copied().unwrap_or(CaseKind::Tracking)
}

/// The timing runs' stereo rig at `width × height` (the board profile's frame size): f = 200 px
/// at 160 px wide, scaled with the width so every profile sees the same view, principal point
/// at the centre, 0.1 m baseline.
///
/// # Errors
/// [`FrameError`] for a size the camera model refuses (zero).
pub fn rig_for(width: u16, height: u16) -> Result<StereoRig, FrameError> {
    let f = 200.0 * f32::from(width) / 160.0;
    let cam = Pinhole::new_checked(f, f, f32::from(width) / 2.0, f32::from(height) / 2.0, width, height)
        .map_err(|_| FrameError)?;
    StereoRig::parallel(cam, 0.1).map_err(|_| FrameError)
}

/// xorshift32: the noise generator of the frames (not the GA's generator).
#[derive(Debug, Clone, Copy)]
pub struct XorShift32(u32);

impl XorShift32 {
    /// A generator; a zero seed is replaced by 1.
    pub fn new(seed: u32) -> Self {
        Self(if seed == 0 { 1 } else { seed })
    }

    /// The next number.
    pub fn next_u32(&mut self) -> u32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        x
    }

    /// A uniform number in `[lo, hi)`.
    pub fn uniform(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * ((self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0))
    }
}

/// Why a frame could not be made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FrameError;

/// Makes the frames and joint samples of a run on the board.
///
/// The target is fixed in the world (slowly drifting) while the PA-10 carries the cameras
/// along [`CaseGen::joints`], so the feedforward of the arm's motion is the right one, as in
/// operation.
#[derive(Debug, Clone)]
pub struct CaseGen {
    rig: StereoRig,
    flange_to_camera: Isometry3<f32>,
    world_from_block: Isometry3<f32>,
    width: usize,
    height: usize,
    rng: XorShift32,
    /// The first frame of the current conveyor block (its motion starts there).
    conveyor_from: Option<u32>,
}

impl CaseGen {
    /// The target's pose in `Σ_CR` at frame 0.
    pub const START: Psi = Psi::new([-0.05, 0.01, 0.6], [0.0, 0.0, 0.5]);

    /// A generator for `rig` (both cameras of one size) on a PA-10 flange at
    /// `flange_to_camera`; the same `seed` gives the same frames.
    ///
    /// # Errors
    /// [`FrameError`] if [`CaseGen::START`] is not a valid pose (never).
    pub fn new(rig: StereoRig, flange_to_camera: Isometry3<f32>, seed: u32) -> Result<Self, FrameError> {
        let (width, height) = (usize::from(rig.right.width()), usize::from(rig.right.height()));
        let cam0 = PA10.forward(&Self::joints(0, false).q) * flange_to_camera;
        let start = Self::START.try_to_isometry().map_err(|_| FrameError)?;
        Ok(Self {
            rig,
            flange_to_camera,
            world_from_block: cam0 * start,
            width,
            height,
            rng: XorShift32::new(seed),
            conveyor_from: None,
        })
    }

    /// The target's true pose in `Σ_CR` at frame `k` (arm at [`CaseGen::joints`]`(k, fast)`):
    /// fixed in the world but for a slow drift (a few cm, a few degrees).
    pub fn truth(&self, k: u32, fast: bool) -> Psi {
        let cam = PA10.forward(&Self::joints(k, fast).q) * self.flange_to_camera;
        Psi::from_isometry(&(cam.inverse() * self.drifting(k)))
    }

    /// `^W T_M` of the target fixed in the world but for the slow drift at frame `k`.
    fn drifting(&self, k: u32) -> Isometry3<f32> {
        let t = k as f32 * (FRAME_PERIOD_US as f32 * 1e-6);
        let s = |w: f32| evorec_core::math::sin(w * t);
        let drift = Isometry3::from_parts(
            Translation3::new(0.03 * s(1.1), 0.02 * s(0.7), 0.05 * s(0.5)),
            UnitQuaternion::from_scaled_axis(Vector3::new(0.1 * s(0.9), 0.15 * s(0.6), 0.2 * s(0.4))),
        );
        self.world_from_block * drift
    }

    /// The target's true pose in `Σ_CR` at frame `k` of a conveyor block that began at frame
    /// `from`: [`CaseGen::truth`] moved along world y by the conveyor, at
    /// [`CONVEYOR_SPEED_M_S`] back and forth over [`CONVEYOR_TRAVEL_M`] (0 at `from`, so the
    /// block continues the path of the frames before it).
    pub fn truth_on_conveyor(&self, k: u32, from: u32) -> Psi {
        let t = k.saturating_sub(from) as f32 * (FRAME_PERIOD_US as f32 * 1e-6);
        let period = 2.0 * CONVEYOR_TRAVEL_M / CONVEYOR_SPEED_M_S;
        let phase = CONVEYOR_SPEED_M_S * (t - period * evorec_core::math::floor(t / period));
        let y = if phase <= CONVEYOR_TRAVEL_M { phase } else { 2.0 * CONVEYOR_TRAVEL_M - phase };
        let cam = PA10.forward(&Self::joints(k, false).q) * self.flange_to_camera;
        Psi::from_isometry(&(cam.inverse() * Translation3::new(0.0, y, 0.0) * self.drifting(k)))
    }

    /// Joint sample of frame `k`: a sinusoid about a bent PA-10 pose, `q̇ ≠ 0`; `fast`
    /// multiplies the joint amplitudes and speeds by 4 (joint speeds up to about 0.5 rad/s).
    pub fn joints(k: u32, fast: bool) -> JointSample<7> {
        let t = k as f32 * (FRAME_PERIOD_US as f32 * 1e-6);
        let q0 = [0.1, 0.4, -0.1, 1.2, 0.05, 0.6, 0.0];
        let amp = [0.05, -0.04, 0.03, 0.05, -0.03, 0.04, 0.06];
        let (w, gain) = if fast { (2.0, 4.0) } else { (2.0, 1.0) };
        let (s, c) = evorec_core::math::sin_cos(w * t);
        JointSample {
            q: core::array::from_fn(|i| q0[i] + amp[i] * s * gain),
            qd: core::array::from_fn(|i| amp[i] * w * c * gain),
            time_us: u64::from(k) * FRAME_PERIOD_US,
        }
    }

    fn render(&self, psi: &Psi, left: &mut [u8], right: &mut [u8]) -> Result<(), FrameError> {
        let iso = psi.try_to_isometry().map_err(|_| FrameError)?;
        synth::render_block(&Block::PAPER, &self.rig.right, &iso, right).map_err(|_| FrameError)?;
        synth::render_block(&Block::PAPER, &self.rig.left, &(self.rig.left_from_right * iso), left)
            .map_err(|_| FrameError)
    }

    fn random_pose(&mut self) -> Psi {
        let r = &mut self.rng;
        let mut p = Psi::new(
            [r.uniform(-0.12, 0.12), r.uniform(-0.09, 0.09), r.uniform(0.45, 0.95)],
            [r.uniform(-0.7, 0.7), r.uniform(-0.7, 0.7), r.uniform(-0.7, 0.7)],
        );
        p.project_to_ball();
        p
    }

    /// Replaces every `every`-th pixel (on average) of an RGB565 image by a random value.
    fn noise(&mut self, img: &mut [u8], every: u32) {
        for px in img.chunks_exact_mut(2) {
            let x = self.rng.next_u32();
            if x.is_multiple_of(every) {
                px.copy_from_slice(&((x >> 8) as u16).to_le_bytes());
            }
        }
    }

    /// Sets every pixel of an RGB565 image to one of [`RGB565_EXTREMES`] at random.
    fn extremes(&mut self, img: &mut [u8]) {
        for px in img.chunks_exact_mut(2) {
            let i = (self.rng.next_u32() >> 8) as usize % RGB565_EXTREMES.len();
            let v = RGB565_EXTREMES.get(i).copied().unwrap_or(0);
            px.copy_from_slice(&v.to_le_bytes());
        }
    }

    fn patches(&mut self, img: &mut [u8]) {
        // Hue units 30, 90, 150 (60°, 180°, 300°): half-way between the faces' 0°, 120°, 240°.
        const DISTRACTORS: [u8; 3] = [30, 90, 150];
        for i in 0..6u32 {
            let w = 8 + (self.rng.next_u32() as usize % (self.width / 3));
            let h = 8 + (self.rng.next_u32() as usize % (self.height / 3));
            let x0 = self.rng.next_u32() as usize % (self.width - w);
            let y0 = self.rng.next_u32() as usize % (self.height - h);
            let hue = DISTRACTORS.get(i as usize % 3).copied().unwrap_or(NO_HUE);
            for row in img.chunks_exact_mut(self.width).skip(y0).take(h) {
                if let Some(span) = row.get_mut(x0..x0 + w) {
                    span.fill(hue);
                }
            }
        }
    }

    /// Writes frame `k` of `kind` into `left`/`right` as RGB565 (each `2 · width · height`
    /// bytes) and returns its joint sample. The scene is drawn as hue bytes into the first
    /// `width · height` bytes of each buffer and expanded in place to RGB565; noise and the
    /// extremes are then written as RGB565 values.
    ///
    /// # Errors
    /// [`FrameError`] if a buffer is too small.
    // Never inlined: the frame's temporaries stay out of the caller's frame, which is on the
    // stack during the measured generation.
    #[inline(never)]
    pub fn frame(
        &mut self,
        k: u32,
        kind: CaseKind,
        left: &mut [u8],
        right: &mut [u8],
    ) -> Result<JointSample<7>, FrameError> {
        let n = self.width * self.height;
        let (left, right) = (left.get_mut(..2 * n).ok_or(FrameError)?, right.get_mut(..2 * n).ok_or(FrameError)?);
        let kind = image_kind(k, kind);
        if kind != CaseKind::Conveyor {
            self.conveyor_from = None;
        }
        self.draw_hues(k, kind, left, right)?;
        expand_hue_to_rgb565(left, n).map_err(|_| FrameError)?;
        expand_hue_to_rgb565(right, n).map_err(|_| FrameError)?;
        match kind {
            CaseKind::Noise => {
                self.noise(left, 1);
                self.noise(right, 1);
            }
            CaseKind::NoisyTarget => {
                self.noise(left, 4);
                self.noise(right, 4);
            }
            CaseKind::Rgb565Extremes => {
                self.extremes(left);
                self.extremes(right);
            }
            _ => {}
        }
        Ok(Self::joints(k, kind == CaseKind::FastArm))
    }

    /// The hue stage of [`CaseGen::frame`]: the scene as hue bytes in the first
    /// `width · height` bytes of each buffer.
    fn draw_hues(&mut self, k: u32, kind: CaseKind, left: &mut [u8], right: &mut [u8]) -> Result<(), FrameError> {
        let n = self.width * self.height;
        let (left, right) = (left.get_mut(..n).ok_or(FrameError)?, right.get_mut(..n).ok_or(FrameError)?);
        left.fill(NO_HUE);
        right.fill(NO_HUE);
        match kind {
            // The image kind of a forced-status frame is never itself a forced-status kind.
            CaseKind::Searching | CaseKind::Lost => {}
            CaseKind::Tracking | CaseKind::FastArm => {
                let p = self.truth(k, kind == CaseKind::FastArm);
                self.render(&p, left, right)?;
            }
            CaseKind::Conveyor => {
                let from = *self.conveyor_from.get_or_insert(k);
                let p = self.truth_on_conveyor(k, from);
                self.render(&p, left, right)?;
            }
            CaseKind::RandomPose => {
                let p = self.random_pose();
                self.render(&p, left, right)?;
            }
            CaseKind::Blank | CaseKind::Noise | CaseKind::Rgb565Extremes => {}
            CaseKind::Absent => {
                self.patches(left);
                self.patches(right);
            }
            CaseKind::Filling => {
                // Turned 90° about y, the 0.2 × 0.15 m side faces the cameras from 0.11 m:
                // about 360 × 270 px at f = 200 px, more than either 160×120 image.
                let x = -0.05 + self.rng.uniform(-0.005, 0.005);
                let p = Psi::new([x, 0.0, 0.16], [0.0, core::f32::consts::FRAC_1_SQRT_2, 0.0]);
                self.render(&p, left, right)?;
            }
            CaseKind::UniformHue => {
                let face = (self.rng.next_u32() % 3) as usize;
                let hue = hue::degrees_to_units(Block::PAPER.face_hues_deg.get(face).copied().unwrap_or(0.0));
                left.fill(hue);
                right.fill(hue);
            }
            CaseKind::NoisyTarget => {
                let p = self.truth(k, false);
                self.render(&p, left, right)?;
            }
        }
        Ok(())
    }
}

/// The image drawn for frame `k` of `kind`: the forced-status kinds show, in turn, the target at
/// a random pose, every pixel one face's hue and the target under noise (searching), or the
/// target on its path, the target filling the image and pure noise (lost); every other kind
/// is its own image.
fn image_kind(k: u32, kind: CaseKind) -> CaseKind {
    let turn = |kinds: [CaseKind; 3]| kinds.get((k % 3) as usize).copied().unwrap_or(CaseKind::Tracking);
    match kind {
        CaseKind::Searching => turn([CaseKind::RandomPose, CaseKind::UniformHue, CaseKind::NoisyTarget]),
        CaseKind::Lost => turn([CaseKind::Tracking, CaseKind::Filling, CaseKind::Noise]),
        other => other,
    }
}

/// Watchdog-style deadline of one generation, in instructions: the project's per-generation
/// budget (`evorec timing`'s `GENERATION_BUDGET`). The timing firmware checks every measured
/// generation against it and prints a [`DeadlineReport`] per run.
pub const DEADLINE_INSTRUCTIONS: u32 = 1_000_000;

/// TIMER0 ticks of [`DEADLINE_INSTRUCTIONS`] under `-icount shift=`[`ICOUNT_SHIFT`].
pub const DEADLINE_TICKS: u32 = ((DEADLINE_INSTRUCTIONS as u64) << ICOUNT_SHIFT).div_ceil(NS_PER_TICK) as u32;

/// The deadline check of one run: `DEADLINE limit=… checked=… missed=… worst=…` (ticks).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DeadlineReport {
    /// Generations checked.
    pub checked: u32,
    /// Generations whose call took longer than [`DEADLINE_TICKS`].
    pub missed: u32,
    /// Ticks of the longest generation.
    pub worst: u32,
}

impl DeadlineReport {
    /// Checks one generation of `call` ticks; true if it met the deadline.
    pub fn check(&mut self, call: u32) -> bool {
        self.checked += 1;
        self.worst = self.worst.max(call);
        let met = call <= DEADLINE_TICKS;
        if !met {
            self.missed += 1;
        }
        met
    }

    /// Parses a line printed by `Display`; `None` for any other line.
    pub fn parse(line: &str) -> Option<Self> {
        let mut words = line.split_whitespace();
        if words.next()? != "DEADLINE" {
            return None;
        }
        let mut r = Self::default();
        for word in words {
            let (key, value) = word.split_once('=')?;
            match key {
                "checked" => r.checked = value.parse().ok()?,
                "missed" => r.missed = value.parse().ok()?,
                "worst" => r.worst = value.parse().ok()?,
                _ => {}
            }
        }
        Some(r)
    }
}

impl fmt::Display for DeadlineReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "DEADLINE limit={} checked={} missed={} worst={}",
            DEADLINE_TICKS, self.checked, self.missed, self.worst
        )
    }
}

/// One measured generation, as printed by the firmware and parsed by the host.
///
/// `GEN p=40 g=8 k=3 kind=blank status=lost method=ff+target tshift=1 call=… ff=… eval=… breed=…
/// stack=… fitness=…`: the status the generation started in, the feedforward mode
/// ([`Feedforward::name`]) and whether the generation fed a non-zero target velocity forward
/// (`tshift`: `Tracker::target_feedforward_velocity`, the target motion model's velocity, which
/// the generation adds to every individual's shift, is not zero), ticks of the whole `step_probed` call and of its three phases, the painted
/// stack high-water mark of the generation (bytes below the top of RAM) and the estimate's
/// fitness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GenLine {
    /// Population size.
    pub population: u32,
    /// Points per row.
    pub grid: u32,
    /// Frame index in the run.
    pub frame: u32,
    /// Kind of frame.
    pub kind: CaseKind,
    /// The tracker's status when the generation started.
    pub status: Status,
    /// The feedforward mode of the generation.
    pub method: Feedforward,
    /// Whether the generation shifted every individual by a non-zero target velocity too.
    pub target_shift: bool,
    /// Ticks of the whole `step_probed` call (input checks included).
    pub call: u32,
    /// Ticks of each phase.
    pub phases: PhaseTicks,
    /// Stack high-water mark of this generation (bytes from the top of RAM).
    pub stack: u32,
    /// Fitness of the estimate.
    pub fitness: f32,
}

impl fmt::Display for GenLine {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "GEN p={} g={} k={} kind={} status={} method={} tshift={} call={} ff={} eval={} breed={} stack={} \
             fitness={}",
            self.population,
            self.grid,
            self.frame,
            self.kind.name(),
            self.status.as_str(),
            self.method,
            u8::from(self.target_shift),
            self.call,
            self.phases.feedforward,
            self.phases.evaluate,
            self.phases.breed,
            self.stack,
            self.fitness
        )
    }
}

impl GenLine {
    /// Parses a line printed by [`GenLine`]'s `Display`; `None` for any other line.
    pub fn parse(line: &str) -> Option<Self> {
        let mut words = line.split_whitespace();
        if words.next()? != "GEN" {
            return None;
        }
        let mut g = GenLine {
            population: 0,
            grid: 0,
            frame: 0,
            kind: CaseKind::Tracking,
            status: Status::Tracking,
            method: Feedforward::On,
            target_shift: false,
            call: 0,
            phases: PhaseTicks::default(),
            stack: 0,
            fitness: 0.0,
        };
        let mut seen = 0u16;
        for word in words {
            let (key, value) = word.split_once('=')?;
            let (slot, bit) = match key {
                "p" => (&mut g.population, 0),
                "g" => (&mut g.grid, 1),
                "k" => (&mut g.frame, 2),
                "call" => (&mut g.call, 3),
                "ff" => (&mut g.phases.feedforward, 4),
                "eval" => (&mut g.phases.evaluate, 5),
                "breed" => (&mut g.phases.breed, 6),
                "stack" => (&mut g.stack, 7),
                "kind" => {
                    g.kind = CaseKind::from_name(value)?;
                    seen |= 1 << 8;
                    continue;
                }
                "fitness" => {
                    g.fitness = value.parse().ok()?;
                    seen |= 1 << 9;
                    continue;
                }
                "status" => {
                    g.status = Status::ALL.into_iter().find(|s| s.as_str() == value)?;
                    seen |= 1 << 10;
                    continue;
                }
                "method" => {
                    g.method = value.parse().ok()?;
                    seen |= 1 << 11;
                    continue;
                }
                "tshift" => {
                    g.target_shift = match value {
                        "0" => false,
                        "1" => true,
                        _ => return None,
                    };
                    seen |= 1 << 12;
                    continue;
                }
                _ => continue,
            };
            *slot = value.parse().ok()?;
            seen |= 1 << bit;
        }
        (seen == 0x1fff).then_some(g)
    }
}

#[cfg(test)]
mod tests;
