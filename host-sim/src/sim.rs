//! The simulated camera-controller board: the PA-10 with its stereo cameras looking at the
//! rotating block, seen by the tracker only through [`CameraController`].
//!
//! Time runs in 1 ms joint-control steps ([`crate::arm::CONTROL_PERIOD_S`]); frame `n` is
//! captured at `t = n · frame_period_s`, rendered in RGB for both cameras, converted to hue
//! with the core's `rgb_to_hue`, and handed over together with the joint sample `q, q̇` of that
//! instant. Each published estimate is stored with the ground truth of its frame.

use anyhow::{Context, Result, bail};
use evorec_core::board::{CameraController, Error as BoardError, ErrorKind, ErrorType, FrameInfo};
use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::status::Status;
use evorec_core::tracker::{Estimate, JointSample};
use nalgebra::Isometry3;
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::arm::{self, ArmSim, CONTROL_PERIOD_S, DOF};
use crate::motion::{FlangeTrajectory, TargetMotion};
use crate::occlusion::{self, OcclusionKind};
use crate::render::{self, AntiAlias, RenderOptions, StereoImages};
use crate::scenario::Scenario;

/// The stereo rig of a scenario (both cameras share the intrinsics).
///
/// # Errors
/// Invalid intrinsics or baseline (scenario validation normally catches them first).
pub fn rig(s: &Scenario) -> Result<StereoRig> {
    let c = &s.camera;
    let cam = Pinhole::new_checked(c.fx as f32, c.fy as f32, c.cx as f32, c.cy as f32, c.width, c.height)
        .map_err(|e| anyhow::anyhow!("camera: {e}"))?;
    StereoRig::parallel(cam, c.baseline_m as f32).map_err(|e| anyhow::anyhow!("camera.baseline_m: {e}"))
}

/// The block of a scenario.
pub fn block(s: &Scenario) -> Block {
    Block { size_m: s.target.size_m.map(|v| v as f32), face_hues_deg: s.target.face_hues_deg.map(|v| v as f32) }
}

/// The world of one run: arm, scripted motions, cameras, target, renderer.
pub struct World {
    scenario: Scenario,
    arm: ArmSim,
    trajectory: FlangeTrajectory,
    target: TargetMotion,
    rig: StereoRig,
    block: Block,
    render: RenderOptions,
    rng: Xoshiro256PlusPlus,
}

impl World {
    /// The world of `scenario` at `t = 0`, the arm at the initial pose.
    ///
    /// # Errors
    /// If the initial arm pose has no inverse-kinematics solution or the camera is invalid.
    pub fn new(scenario: &Scenario) -> Result<Self> {
        let arm = ArmSim::at_start().map_err(|e| anyhow::anyhow!("initial arm pose: {e:?}"))?;
        let antialias = match scenario.camera.supersample {
            0 | 1 => AntiAlias::Off,
            n => AntiAlias::Supersample(n.min(16) as u8),
        };
        Ok(Self {
            scenario: *scenario,
            arm,
            trajectory: FlangeTrajectory::from_scenario(scenario),
            target: TargetMotion::from_scenario(scenario),
            rig: rig(scenario)?,
            block: block(scenario),
            render: RenderOptions::default().with_antialias(antialias).with_noise(scenario.camera.noise_std as f32),
            rng: Xoshiro256PlusPlus::seed_from_u64(scenario.seed ^ 0x5EED_0FF4_A3E5),
        })
    }

    /// The scenario.
    pub fn scenario(&self) -> &Scenario {
        &self.scenario
    }

    /// The stereo rig.
    pub fn rig(&self) -> &StereoRig {
        &self.rig
    }

    /// The block.
    pub fn block(&self) -> &Block {
        &self.block
    }

    /// The arm.
    pub fn arm(&self) -> &ArmSim {
        &self.arm
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.arm.time()
    }

    /// Runs the 1 ms joint control loop up to time `t` (s).
    pub fn advance_to(&mut self, t: f64) {
        while self.arm.time() + 0.5 * CONTROL_PERIOD_S < t {
            self.arm.follow(CONTROL_PERIOD_S, &self.trajectory);
        }
    }

    /// `^W T_CR`: the right camera's pose from the arm's forward kinematics.
    pub fn camera_pose(&self) -> Isometry3<f64> {
        self.arm.camera_pose(self.scenario.camera.baseline_m)
    }

    /// `^W T_M` at the current time.
    pub fn target_pose(&self) -> Isometry3<f64> {
        self.target.target_world_pose(self.arm.time())
    }

    /// `^CR T_M`: the target in the right camera frame (computed in f64).
    pub fn target_in_camera(&self) -> Isometry3<f64> {
        self.camera_pose().inverse() * self.target_pose()
    }

    /// The true pose `^CR ψ_M` now (η ≥ 0).
    pub fn truth(&self) -> Psi {
        let iso: Isometry3<f32> = self.target_in_camera().cast();
        Psi::from_isometry(&iso)
    }

    /// The occlusion hiding the block now, if any (`[[occlusion]]` of the scenario).
    pub fn occlusion(&self) -> Option<OcclusionKind> {
        self.scenario.occlusion.at(self.arm.time())
    }

    /// Renders both cameras' RGB images at the current time, with the scenario's occlusions:
    /// a removed block is not drawn, an occluder is painted over the block's image.
    pub fn render(&mut self) -> StereoImages {
        let pose: Isometry3<f32> = self.target_in_camera().cast();
        match self.occlusion() {
            None => render::render_stereo(&self.rig, &pose, &self.block, &self.render, &mut self.rng),
            Some(OcclusionKind::Removed) => {
                // A block behind the cameras renders as the background alone.
                let gone = Isometry3::translation(0.0, 0.0, -10.0);
                render::render_stereo(&self.rig, &gone, &self.block, &self.render, &mut self.rng)
            }
            Some(OcclusionKind::Occluder) => {
                let mut images = render::render_stereo(&self.rig, &pose, &self.block, &self.render, &mut self.rng);
                let right = occlusion::corners_in(&pose, &self.block);
                let left = occlusion::corners_in(&(self.rig.left_from_right * pose), &self.block);
                occlusion::paint_occluder(&mut images.right, &self.rig.right, &right);
                occlusion::paint_occluder(&mut images.left, &self.rig.left, &left);
                images
            }
        }
    }
}

/// One row of `trace.csv`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TraceRow {
    /// Capture time (s).
    pub t: f64,
    /// Joint angles (rad).
    pub q: [f32; DOF],
    /// Joint velocities (rad/s).
    pub qd: [f32; DOF],
    /// True pose in `Σ_CR`.
    pub truth: Psi,
    /// Estimate.
    pub estimate: Psi,
    /// Its fitness.
    pub fitness: f32,
    /// The tracker's status.
    pub status: Status,
    /// The block was hidden (occluded or removed) in this frame.
    pub hidden: bool,
}

/// Why the simulated board stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SimError {
    /// All frames of the scenario were delivered.
    EndOfStream,
    /// The caller's buffers are smaller than a frame.
    BufferTooSmall,
}

impl BoardError for SimError {
    fn kind(&self) -> ErrorKind {
        match self {
            Self::EndOfStream => ErrorKind::EndOfStream,
            Self::BufferTooSmall => ErrorKind::Other,
        }
    }
}

/// The simulated board.
pub struct SimBoard {
    world: World,
    frames: u32,
    next: u32,
    current: Option<(f64, Psi, JointSample<DOF>, bool)>,
    rows: Vec<TraceRow>,
}

impl SimBoard {
    /// A board delivering [`frame_total`] frames of `world`'s scenario.
    pub fn new(world: World) -> Self {
        let frames = frame_total(world.scenario());
        Self { world, frames, next: 0, current: None, rows: Vec::with_capacity(frames as usize) }
    }

    /// Frames this board delivers in all.
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// The world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The rows recorded so far.
    pub fn rows(&self) -> &[TraceRow] {
        &self.rows
    }

    /// Takes the recorded rows.
    pub fn into_rows(self) -> Vec<TraceRow> {
        self.rows
    }
}

impl ErrorType for SimBoard {
    type Error = SimError;
}

impl CameraController<DOF> for SimBoard {
    fn next_frame(&mut self, left: &mut [u8], right: &mut [u8]) -> Result<FrameInfo, SimError> {
        if self.next >= self.frames {
            return Err(SimError::EndOfStream);
        }
        let cam = self.world.rig().right;
        let n = usize::from(cam.width()) * usize::from(cam.height());
        if left.len() < n || right.len() < n {
            return Err(SimError::BufferTooSmall);
        }
        let t = f64::from(self.next) * self.world.scenario().frame_period_s;
        self.world.advance_to(t);
        let images = self.world.render();
        render::hue_into(&images.left, left);
        render::hue_into(&images.right, right);
        let joints = self.world.arm().joint_sample();
        self.current = Some((t, self.world.truth(), joints, self.world.occlusion().is_some()));
        let info = FrameInfo {
            sequence: self.next,
            capture_time_us: (t * 1e6).round() as u64,
            width: cam.width(),
            height: cam.height(),
        };
        self.next += 1;
        Ok(info)
    }

    fn joint_sample(&mut self) -> Result<JointSample<DOF>, SimError> {
        Ok(self.world.arm().joint_sample())
    }

    fn publish(&mut self, _frame: &FrameInfo, estimate: &Estimate) -> Result<(), SimError> {
        if let Some((t, truth, joints, hidden)) = self.current.take() {
            self.rows.push(TraceRow {
                t,
                q: joints.q,
                qd: joints.qd,
                truth,
                estimate: estimate.psi,
                fitness: estimate.fitness,
                status: estimate.status,
                hidden,
            });
        }
        Ok(())
    }
}

/// Frames of a run: `round(duration / frame_period) + 1` (frames at `t = 0, T, 2T, …`).
pub fn frame_total(s: &Scenario) -> u32 {
    (s.duration_s / s.frame_period_s).round() as u32 + 1
}

/// Checks a frame index against a scenario and returns its capture time.
///
/// # Errors
/// If the frame is past the end of the scenario.
pub fn frame_time(s: &Scenario, frame: u32) -> Result<f64> {
    let t = f64::from(frame) * s.frame_period_s;
    if t > s.duration_s + 1e-9 {
        bail!("frame {frame} is at t = {t:.3} s, after the scenario's end ({} s)", s.duration_s);
    }
    Ok(t)
}

/// The flange-to-camera transform of a scenario (f32, for the tracker).
pub fn flange_to_camera(s: &Scenario) -> Isometry3<f32> {
    arm::flange_to_camera(s.camera.baseline_m)
}

/// Renders the frame at `frame` of a scenario (advancing a fresh world to its time).
///
/// # Errors
/// As [`World::new`] and [`frame_time`].
pub fn world_at_frame(s: &Scenario, frame: u32) -> Result<World> {
    let t = frame_time(s, frame)?;
    let mut world = World::new(s).context("building the simulated world")?;
    world.advance_to(t);
    Ok(world)
}
