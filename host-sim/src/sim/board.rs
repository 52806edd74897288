//! The simulated camera-controller board: the PA-10 with its stereo cameras looking at the
//! rotating block, seen by the tracker only through [`CameraController`].
//!
//! Time runs in 1 ms joint-control steps ([`crate::sim::arm::CONTROL_PERIOD_S`]); frame `n` is
//! captured at `t = n · frame_period_s`, rendered in RGB for both cameras, packed into the
//! RGB565 pixels a camera sensor delivers ([`render::rgb565_into`]), and handed over together
//! with the joint sample `q, q̇` of that instant; the tracker computes the hue of the pixels it
//! samples, as the board does (`evorec run` and `evorec hil` see the same bytes). Each published estimate is stored with the ground truth of its frame.
//!
//! One board, [`SimBoard`], serves every run; what moves the arm between frames and consumes
//! the estimates is its pluggable [`ArmController`]: the scenario's scripted flange motion
//! ([`Scripted`], `evorec run`) or the visual servo ([`crate::experiments::closed_loop::ServoLoop`], a
//! `[servo]` scenario). A host tracker for a board is set up by
//! [`crate::experiments::experiment::setup_tracker`].
//!
//! ## Hand-over
//! [`Scripted`] also plays the consumer of the estimates (a visual-servo loop): the estimate of
//! the frame captured at `t` is output at `t + delay_s` (`[start] delay_s`). It feeds
//! every published estimate to its own copy of the core's [`TargetFilter`] with the tracker's
//! own call, [`TargetFilter::update_from_estimate`], on the measurement the estimate carries
//! ([`Estimate::target_measurement`]): the same code on the same inputs as the tracker's
//! filter, so it works for the firmware too, which publishes the estimate only. It asks that
//! filter for the pose at the output time with the arm's joint sample of that time
//! ([`TargetFilter::predict`]). Each row records the truth at the output time, the held
//! estimate and the prediction ([`Handover`]).
use anyhow::{Context, Result, bail};
use evorec_core::board::{CameraController, Error as BoardError, ErrorKind, ErrorType, FrameInfo};
use evorec_core::camera::{Pinhole, StereoRig};
use evorec_core::ga::SearchSpace;
use evorec_core::kinematics::PA10;
use evorec_core::model::Block;
use evorec_core::pose::Psi;
use evorec_core::status::Status;
use evorec_core::target_motion::{Optics, TargetFilter, TargetVelocity};
use evorec_core::tracker::{Estimate, JointSample};
use nalgebra::Isometry3;
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::sim::arm::{ArmSim, CONTROL_PERIOD_S, DOF};
use crate::sim::motion::{self, FlangeTrajectory, TargetMotion, Twist};
use crate::sim::occlusion::{self, OcclusionKind, Placement};
use crate::sim::render::{self, AntiAlias, RenderOptions, StereoImages};
use crate::sim::scenario::Scenario;
use crate::sim::target_path::{self, TargetPath};

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

/// The search space in `Σ_CR`: ±0.4 m laterally, 0.3–1.3 m deep.
pub fn search_space() -> SearchSpace {
    // The bounds are constants that satisfy the checks.
    SearchSpace::new_checked([-0.4, -0.4, 0.3], [0.4, 0.4, 1.3]).unwrap_or_else(|e| unreachable!("{e}"))
}

/// The world of one run: arm, scripted motions, cameras, target, renderer.
pub struct World {
    scenario: Scenario,
    arm: ArmSim,
    trajectory: FlangeTrajectory,
    target: TargetMotion,
    path: TargetPath,
    rig: StereoRig,
    block: Block,
    render: RenderOptions,
    rng: Xoshiro256PlusPlus,
    hidden: bool,
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
            trajectory: flange_trajectory(scenario),
            target: target_motion(scenario),
            path: TargetPath::from_scenario(scenario),
            rig: rig(scenario)?,
            block: block(scenario),
            render: RenderOptions::default()
                .with_antialias(antialias)
                .with_noise(scenario.camera.noise_std as f32)
                .with_light(scenario.render),
            rng: Xoshiro256PlusPlus::seed_from_u64(scenario.seed ^ 0x5EED_0FF4_A3E5),
            hidden: false,
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

    /// Runs the 1 ms joint control loop up to time `t` (s) in closed loop: before every
    /// control period `control` gives the flange setpoint (pose and world twist at the flange
    /// origin) instead of the scripted trajectory.
    pub fn advance_with(&mut self, t: f64, mut control: impl FnMut(&ArmSim) -> (Isometry3<f64>, Twist)) {
        while self.arm.time() + 0.5 * CONTROL_PERIOD_S < t {
            let (pose, twist) = control(&self.arm);
            self.arm.step(CONTROL_PERIOD_S, &pose, &twist);
        }
    }

    /// Hides the block from both cameras (an occluder in front of them) or shows it again.
    pub fn set_target_hidden(&mut self, hidden: bool) {
        self.hidden = hidden;
    }

    /// Replaces the block's own path (e.g. a conveyor of a closed-loop experiment that the
    /// scenario file does not describe).
    pub fn set_target_path(&mut self, path: TargetPath) {
        self.path = path;
    }

    /// The block's own path.
    pub fn target_path(&self) -> &TargetPath {
        &self.path
    }

    /// `^W T_CR`: the right camera's pose from the arm's forward kinematics.
    pub fn camera_pose(&self) -> Isometry3<f64> {
        self.arm.camera_pose(self.scenario.camera.baseline_m)
    }

    /// `^W T_M` at the current time.
    pub fn target_pose(&self) -> Isometry3<f64> {
        self.target_pose_at(self.arm.time())
    }

    fn target_pose_at(&self, t: f64) -> Isometry3<f64> {
        target_path::target_pose(&self.target, &self.path, t)
    }

    /// The block's true velocity in the world at the current time (scripted motion and path),
    /// as the target model states it.
    pub fn target_velocity(&self) -> TargetVelocity {
        let tw = target_path::target_twist(&self.target, &self.path, self.arm.time());
        TargetVelocity { v: tw.v.cast(), w: tw.w.cast() }
    }

    /// The true pose `^CR ψ_M` and the joint sample at a later time `t` along the scripted
    /// trajectory, without advancing this world (a copy of the arm runs ahead).
    pub fn look_ahead(&self, t: f64) -> (Psi, JointSample<DOF>) {
        let mut arm = self.arm.clone();
        while arm.time() + 0.5 * CONTROL_PERIOD_S < t {
            arm.follow(CONTROL_PERIOD_S, &self.trajectory);
        }
        let target = self.target_pose_at(arm.time());
        let iso: Isometry3<f32> = (arm.camera_pose(self.scenario.camera.baseline_m).inverse() * target).cast();
        (Psi::from_isometry(&iso), arm.joint_sample())
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

    /// `^CR T_M` at `τ` s after the current time: the block along its path, the cameras moved
    /// on at the joints' current velocities (`τ = 0`: [`World::target_in_camera`]).
    pub fn target_in_camera_after(&self, tau: f64) -> Isometry3<f64> {
        if tau == 0.0 {
            return self.target_in_camera();
        }
        let (q, qd) = (self.arm.q(), self.arm.qd());
        let q: [f64; DOF] = core::array::from_fn(|i| q[i] + qd[i] * tau);
        let camera = crate::sim::arm::forward(&q) * motion::flange_to_camera_f64(self.scenario.camera.baseline_m);
        camera.inverse() * self.target_pose_at(self.arm.time() + tau)
    }

    /// Renders both cameras' RGB images at the current time, with the scenario's occlusions:
    /// a removed block is not drawn, an occluder is painted over the block's image. With a
    /// `[render] exposure_s` the block is blurred over the exposure from now on
    /// ([`World::target_in_camera_after`] at [`render::Light::blur_times`]).
    pub fn render(&mut self) -> StereoImages {
        let poses: Vec<Isometry3<f32>> =
            self.render.light.blur_times().iter().map(|&tau| self.target_in_camera_after(tau).cast()).collect();
        let pose = poses[0];
        let occlusion = if self.hidden { Some(OcclusionKind::Removed) } else { self.occlusion() };
        let draw = |w: &mut Self, poses: &[Isometry3<f32>]| {
            render::render_stereo_blurred(&w.rig, poses, &w.block, &w.render, &mut w.rng)
        };
        match occlusion {
            None => draw(self, &poses),
            // No pose: the background alone.
            Some(OcclusionKind::Removed) => draw(self, &[]),
            Some(OcclusionKind::Occluder) => {
                let mut images = draw(self, &poses);
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
    /// Its fitness in the left and the right camera (`fitness` is their mean).
    pub camera_fitness: [f32; 2],
    /// The tracker's status.
    pub status: Status,
    /// The block was hidden (occluded or removed) in this frame.
    pub hidden: bool,
    /// The hand-over of this estimate at its output time (`None` where not simulated).
    pub handover: Option<Handover>,
}

/// The estimate of one frame as a consumer sees it at the output time `t + delay`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Handover {
    /// Output time (s).
    pub t_out: f64,
    /// The true pose in `Σ_CR` at the output time and the pose predicted for it by the core's
    /// `TargetFilter::predict` (the held estimate when the filter has no track). `None` in a
    /// closed loop, where the arm's motion up to the output time is not yet known when the
    /// frame is published (its trace then holds the velocities only).
    pub poses: Option<HandedPoses>,
    /// Whether the prediction used a trusted target velocity.
    pub trusted: bool,
    /// The target velocity the prediction used (world).
    pub velocity: TargetVelocity,
    /// The target velocity fed forward to this frame's population in the "ff+target" method
    /// (`TargetFilter::feedforward_velocity` before this estimate; the board's filter has the
    /// same inputs as the tracker's, so it is the tracker's). Zero in every frame means the run
    /// is bit-identical to "ff".
    pub feedforward: TargetVelocity,
    /// The true target velocity at capture (world).
    pub true_velocity: TargetVelocity,
}

/// The poses of a [`Handover`] at its output time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HandedPoses {
    /// True pose in `Σ_CR` at the output time.
    pub truth_out: Psi,
    /// The pose predicted for the output time.
    pub predicted: Psi,
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

/// What the board keeps of the frame it delivered last, until its estimate is published.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capture {
    /// Capture time (s).
    pub t: f64,
    /// True pose `^CR ψ_M` at capture.
    pub truth: Psi,
    /// The joint sample delivered with the frame.
    pub joints: JointSample<DOF>,
    /// Whether the block was hidden in this frame (as the arm controller says).
    pub hidden: bool,
}

/// What moves the simulated arm between frames and consumes the published estimates: the one
/// part of a [`SimBoard`] that differs between an open-loop run (the scenario's scripted flange
/// motion, [`Scripted`]) and a closed loop (the visual servo,
/// [`crate::experiments::closed_loop::ServoLoop`]).
pub trait ArmController {
    /// Runs the arm (the 1 kHz joint loop) up to `t`, the capture time of the next frame, and
    /// sets the world up for that frame; returns whether the block is hidden in it.
    fn advance(&mut self, world: &mut World, t: f64) -> bool;

    /// Takes the estimate of the frame `capture` (the world still at its capture time); returns
    /// the hand-over the frame's [`TraceRow`] records (`None` where not simulated).
    fn publish(&mut self, world: &World, capture: &Capture, estimate: &Estimate) -> Option<Handover>;
}

/// The scenario's scripted flange motion ([`World::advance_to`]), and a consumer of the
/// estimates that hands each over `[start] delay_s` after capture with its own copy of the
/// target filter (see the module documentation).
pub struct Scripted {
    filter: TargetFilter,
    flange_to_camera: Isometry3<f32>,
}

impl Scripted {
    /// The controller of `s`; its copy of the target filter is tuned by the scenario's
    /// `[target_filter]`, as the tracker's is.
    ///
    /// # Errors
    /// Invalid `[target_filter]` parameters (a scenario read from a file has them checked).
    pub fn new(s: &Scenario) -> Result<Self> {
        Ok(Self { filter: target_filter(s)?, flange_to_camera: flange_to_camera(s) })
    }
}

impl ArmController for Scripted {
    fn advance(&mut self, world: &mut World, t: f64) -> bool {
        world.advance_to(t);
        world.occlusion().is_some()
    }

    /// Updates the target filter with `estimate` and predicts the pose at the output time
    /// `t + delay_s`.
    fn publish(&mut self, world: &World, capture: &Capture, estimate: &Estimate) -> Option<Handover> {
        let true_velocity = world.target_velocity();
        let feedforward = self.filter.feedforward_velocity();
        self.filter.update_from_estimate(
            &PA10,
            &self.flange_to_camera,
            &capture.joints,
            &estimate.target_measurement,
            estimate.status,
        );
        let t_out = capture.t + world.scenario().start.delay_s;
        let (truth_out, joints_out) = world.look_ahead(t_out);
        let t_out_us = (t_out * 1e6).round() as u64;
        let (predicted, trusted, velocity) =
            match self.filter.predict(&PA10, &self.flange_to_camera, &joints_out, t_out_us) {
                Ok(p) => (p.psi, p.trusted, p.velocity),
                Err(_) => (estimate.psi, false, TargetVelocity::ZERO),
            };
        let poses = Some(HandedPoses { truth_out, predicted });
        Some(Handover { t_out, poses, trusted, velocity, feedforward, true_velocity })
    }
}

/// The simulated board: delivers [`frame_total`] frames of its world's scenario, frame `n`
/// captured at `t = n · frame_period_s` after the arm controller `A` ran the arm up to then,
/// rendered as the cameras' RGB565 pixels with the joint sample of that instant; records a
/// [`TraceRow`] per published estimate, after handing the estimate to the controller.
pub struct SimBoard<A = Scripted> {
    world: World,
    arm: A,
    start: Psi,
    frames: u32,
    next: u32,
    current: Option<Capture>,
    rows: Vec<TraceRow>,
}

impl SimBoard<Scripted> {
    /// The open-loop board of `world`'s scenario ([`Scripted`]).
    ///
    /// # Errors
    /// As [`Scripted::new`].
    pub fn new(world: World) -> Result<Self> {
        let arm = Scripted::new(world.scenario())?;
        Ok(Self::with_arm(world, arm))
    }
}

impl<A: ArmController> SimBoard<A> {
    /// A board of `world` (at `t = 0`) whose arm `arm` moves.
    pub fn with_arm(world: World, arm: A) -> Self {
        let frames = frame_total(world.scenario());
        let start = world.truth();
        let rows = Vec::with_capacity(frames as usize);
        Self { world, arm, start, frames, next: 0, current: None, rows }
    }

    /// The true pose when the board was built (`t = 0`), around which a tracker's population
    /// starts when the pose is known.
    pub fn start_pose(&self) -> Psi {
        self.start
    }

    /// Frames this board delivers in all.
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// The world.
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The world, to change before the first frame (e.g. a target path the scenario does not
    /// describe).
    pub fn world_mut(&mut self) -> &mut World {
        &mut self.world
    }

    /// The arm controller.
    pub fn arm(&self) -> &A {
        &self.arm
    }

    /// The rows recorded so far.
    pub fn rows(&self) -> &[TraceRow] {
        &self.rows
    }

    /// Takes the recorded rows.
    pub fn into_rows(self) -> Vec<TraceRow> {
        self.rows
    }

    /// Takes the recorded rows and the arm controller.
    pub fn into_parts(self) -> (Vec<TraceRow>, A) {
        (self.rows, self.arm)
    }
}

impl<A> ErrorType for SimBoard<A> {
    type Error = SimError;
}

impl<A: ArmController> CameraController<DOF> for SimBoard<A> {
    type Format = evorec_core::image::Rgb565;
    fn next_frame(&mut self, left: &mut [u8], right: &mut [u8]) -> Result<FrameInfo, SimError> {
        if self.next >= self.frames {
            return Err(SimError::EndOfStream);
        }
        let cam = self.world.rig().right;
        let n = usize::from(cam.width()) * usize::from(cam.height()) * 2;
        if left.len() < n || right.len() < n {
            return Err(SimError::BufferTooSmall);
        }
        let t = f64::from(self.next) * self.world.scenario().frame_period_s;
        let hidden = self.arm.advance(&mut self.world, t);
        let images = self.world.render();
        render::rgb565_into(&images.left, left);
        render::rgb565_into(&images.right, right);
        let joints = self.world.arm().joint_sample();
        self.current = Some(Capture { t, truth: self.world.truth(), joints, hidden });
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
        let Some(capture) = self.current.take() else { return Ok(()) };
        let handover = self.arm.publish(&self.world, &capture, estimate);
        let Capture { t, truth, joints, hidden } = capture;
        self.rows.push(TraceRow {
            t,
            q: joints.q,
            qd: joints.qd,
            truth,
            estimate: estimate.psi,
            fitness: estimate.fitness,
            camera_fitness: estimate.camera_fitness,
            status: estimate.status,
            hidden,
            handover,
        });
        Ok(())
    }
}

/// Bytes of one of a scenario's RGB565 images (2 per pixel), the size of the buffers
/// [`SimBoard`] fills.
pub fn image_bytes(s: &Scenario) -> usize {
    usize::from(s.camera.width) * usize::from(s.camera.height) * 2
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

/// The target motion model a scenario's `ff+target` runs with (its `[tracker] target.*`, seen
/// through its cameras and block as the tracker's is).
///
/// # Errors
/// Parameters that [`TargetFilter::new`] refuses (a parsed scenario's never are).
pub fn target_filter(s: &Scenario) -> Result<TargetFilter> {
    let filter = TargetFilter::new(s.tuning().target).map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(filter.with_optics(Optics::of(&rig(s)?, &block(s))))
}

/// The flange-to-camera transform of a scenario (f32, for the tracker).
pub fn flange_to_camera(s: &Scenario) -> Isometry3<f32> {
    motion::flange_to_camera(s.camera.baseline_m)
}

/// The flange motion a scenario describes.
pub fn flange_trajectory(s: &Scenario) -> FlangeTrajectory {
    let r = &s.robot;
    let centre = motion::target_centre(s.camera.baseline_m, s.target.distance_m);
    FlangeTrajectory::new(r.motion, r.omega_rad_s, r.amplitude_m, r.amplitude_deg.to_radians(), centre)
}

/// The target motion a scenario describes (with `placement = "random"`, the pose of
/// [`random_target_pose`] and no `yaw0`).
pub fn target_motion(s: &Scenario) -> TargetMotion {
    let fixed = TargetMotion {
        centre: motion::target_centre(s.camera.baseline_m, s.target.distance_m),
        yaw0_rad: s.target.yaw0_deg.to_radians(),
        amplitude_rad: s.target.amplitude_deg.to_radians(),
        omega_rad_s: s.target.omega_rad_s,
        rest: motion::target_rest_rotation(),
    };
    match s.target.placement {
        Placement::Fixed => fixed,
        Placement::Random => match random_target_pose(s) {
            Some(pose) => TargetMotion {
                centre: nalgebra::Point3::from(pose.translation.vector),
                yaw0_rad: 0.0,
                rest: pose.rotation,
                ..fixed
            },
            None => fixed,
        },
    }
}

/// Tries of [`random_target_pose`] before it gives up.
pub const RANDOM_POSE_TRIES: usize = 100_000;

/// Times over the run at which a random pose is checked to be inside both images.
pub const RANDOM_POSE_CHECKS: usize = 40;

/// Margin (pixels) the block's image keeps from every image border in a random pose.
pub const RANDOM_POSE_MARGIN_PX: f32 = 2.0;

/// A random world pose `^W T_M` of the block for the scenario's seed: its centre uniform in
/// the tracker's search space ([`search_space`], in `Σ_CR` at `t = 0`), its
/// orientation uniform (Shoemake's method), redrawn until every corner is at least
/// [`RANDOM_POSE_MARGIN_PX`] inside both images at `t = 0` and, when the flange moves, at
/// [`RANDOM_POSE_CHECKS`] times over the run (along the scripted flange trajectory, with the
/// block at rest: its own yaw oscillation is not checked). `None` after
/// [`RANDOM_POSE_TRIES`] tries.
pub fn random_target_pose(s: &Scenario) -> Option<Isometry3<f64>> {
    use rand_core::{Rng, SeedableRng};
    let rig = rig(s).ok()?;
    let space = search_space();
    let block = block(s);
    let trajectory = flange_trajectory(s);
    let mount = motion::flange_to_camera_f64(s.camera.baseline_m);
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(s.seed ^ 0x9A3D_0B1E_C7F0_5EED);
    let mut unit = move || (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    let inside = |p: &Result<nalgebra::Point2<f32>, _>, cam: &evorec_core::camera::Pinhole| match p {
        Ok(p) => {
            let m = RANDOM_POSE_MARGIN_PX;
            p.x >= m && p.y >= m && p.x <= f32::from(cam.width()) - m && p.y <= f32::from(cam.height()) - m
        }
        Err(_) => false,
    };
    for _ in 0..RANDOM_POSE_TRIES {
        let t: [f64; 3] = core::array::from_fn(|i| {
            let (lo, hi) = (f64::from(space.t_min()[i]), f64::from(space.t_max()[i]));
            lo + (hi - lo) * unit()
        });
        let (u1, u2, u3) = (unit(), unit(), unit());
        let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
        let tau = std::f64::consts::TAU;
        let q = nalgebra::Quaternion::new(
            b * (tau * u3).cos(),
            a * (tau * u2).sin(),
            a * (tau * u2).cos(),
            b * (tau * u3).sin(),
        );
        let q = nalgebra::UnitQuaternion::from_quaternion(q);
        let pose = Isometry3::from_parts(nalgebra::Translation3::new(t[0], t[1], t[2]), q);
        let world = motion::initial_camera_pose(s.camera.baseline_m) * pose;
        let visible_at = |t: f64| {
            let cam = trajectory.setpoint(t).pose * mount;
            let pose32: Isometry3<f32> = (cam.inverse() * world).cast();
            block.corners().iter().all(|c| {
                let (r, l) = rig.project_model_point(&pose32, c);
                inside(&r, &rig.right) && inside(&l, &rig.left)
            })
        };
        let checks = if trajectory.omega_rad_s > 0.0 && trajectory.kind != motion::MotionKind::Static {
            RANDOM_POSE_CHECKS
        } else {
            0
        };
        if visible_at(0.0) && (1..=checks).all(|k| visible_at(s.duration_s * k as f64 / checks as f64)) {
            return Some(world);
        }
    }
    None
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

#[cfg(test)]
mod tests {
    use super::*;
    use evorec_core::tuning::Feedforward;

    /// A 1 s run at 160×120 of the block on a 0.2 m/s conveyor, static arm.
    fn conveyor_run(method: Feedforward) -> Vec<TraceRow> {
        let mut s = Scenario::small(3, 1.0, method);
        s.camera.supersample = 1;
        s.target.conveyor_speed_m_s = 0.2;
        s.target.conveyor_accel_m_s2 = 2.0;
        let out = crate::experiments::experiment::run(&s, || {}).unwrap_or_else(|e| unreachable!("{e}"));
        out.rows
    }

    #[test]
    fn the_hand_over_compares_with_the_truth_one_delay_later() {
        let rows = conveyor_run(Feedforward::On);
        assert_eq!(rows.len(), 31);
        for pair in rows.windows(2) {
            let h = pair[0].handover.unwrap_or_else(|| unreachable!("every frame has a hand-over"));
            // Default delay: one frame period; the truth then is the next frame's.
            assert!((h.t_out - pair[1].t).abs() < 1e-9);
            assert_eq!(h.poses.map(|p| p.truth_out), Some(pair[1].truth));
            // The block rides the conveyor along world y.
            assert_eq!((h.true_velocity.v.x, h.true_velocity.v.z), (0.0, 0.0));
        }
        let last = rows[rows.len() - 1].handover.unwrap_or_else(|| unreachable!());
        assert!(last.true_velocity.v.y > 0.1, "{:?}", last.true_velocity);
    }

    #[test]
    fn the_boards_filter_copy_runs_the_scenarios_tuning() {
        let mut s = Scenario::new(3, 1.0, Feedforward::OnWithTarget);
        s.tracker.0.target.max_gap_s = 0.3;
        let board = SimBoard::new(World::new(&s).unwrap_or_else(|e| unreachable!("{e}")))
            .unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(board.arm.filter.params(), &s.tuning().target);
        // Parameters the core refuses are refused here too, naming the section and the field.
        s.tracker.0.target.image_noise_px = 0.0;
        let e = SimBoard::new(World::new(&s).unwrap_or_else(|e| unreachable!("{e}"))).err().map(|e| e.to_string());
        assert_eq!(e.as_deref(), Some("tracker.target.image_noise_px: must be finite and positive"));
    }

    #[test]
    fn the_target_path_moves_the_rendered_block() {
        let rows = conveyor_run(Feedforward::OnWithTarget);
        let (first, last) = (&rows[0].truth, &rows[rows.len() - 1].truth);
        // Static arm: the truth in the camera moves with the conveyor (sideways, ~0.1 m in 1 s).
        let moved = (last.translation() - first.translation()).norm();
        assert!(moved > 0.05 && moved < 0.2, "moved {moved} m");
    }
}
