//! The closed loop: position-based visual servoing of the simulated PA-10 from the tracker's
//! own estimates (a scenario with `[servo]`).
//!
//! Per frame `n` (captured at `t_n = n·T`):
//! 1. the 1 kHz joint loop runs up to `t_n`; at every period the newest estimate that has
//!    *reached* the servo (captured `delay_frames·T` earlier or more) is handed over to the
//!    command time — taken into the world with the joint state of its capture and seen from
//!    the camera at the current joint state (and, with the target velocity, moved by the
//!    target filter's velocity) —, the core's [`Servo`] turns it into a camera twist, and the
//!    twist is integrated into the flange setpoint that the arm's resolved-rate controller
//!    follows (joint velocity limits, joint-limit avoidance);
//! 2. the frame pair is rendered as the cameras' RGB565 pixels (or the block hidden during an
//!    occlusion) and the tracker runs one generation on it — the host's ([`run`]) or the
//!    firmware's under QEMU (`crate::firmware::hil::run_closed_loop`, `evorec hil`), both through the
//!    same [`ServoBoard`]; the estimate (with the tracker's status) updates the board's copy
//!    of the target filter and is queued until it reaches the servo.
//!
//! The servo moves only on estimates of a block the tracker holds ([`Status::holds`](evorec_core::status::Status::holds): tracking,
//! or uncertain — followed, its pose not confirmed to the stated accuracy; see
//! `evorec_core::status`); otherwise it decelerates to a stop within its limits and resumes when
//! the tracker holds the block again. A velocity servo corrects an approximate pose frame by
//! frame, and a block that manoeuvres is held but uncertain on many frames: a servo that stopped
//! on them would lose it. A robot that acts on the absolute pose (a grasp) waits for tracking.

use std::collections::VecDeque;

use anyhow::{Result, anyhow};
use evorec_core::feedforward::{self, CameraTwist};
use evorec_core::kinematics::PA10;
use evorec_core::pose::Psi;
use evorec_core::servo::{PoseError, Servo, ServoConfig, ServoInput, ServoLimits};
use evorec_core::target_motion::{self, TargetFilter};
use evorec_core::tracker::{Estimate, Feedforward, JointSample};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use serde::Serialize;

use crate::experiments::experiment::{self, Population, ProgressBoard, RunOutput, SimTracker, Summary};
use crate::sim::arm::{ArmSim, CONTROL_PERIOD_S, DOF};
use crate::sim::board::{ArmController, Capture, Handover, SimBoard, World, frame_total};
use crate::sim::motion::Twist;
use crate::sim::motion::flange_to_camera_f64;
use crate::sim::scenario::{Scenario, ServoSection};
use crate::sim::target_path::{Conveyor, TargetPath};

mod compare;
pub use compare::{Comparison, compare};

/// A frame counts towards the steady state only after the conveyor ran at constant speed for
/// this long (s).
pub const STEADY_AFTER_REVERSAL_S: f64 = 1.0;

/// Options of a closed-loop run that scenario files do not carry.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LoopOptions {
    /// Hide the block from `start` for `duration` seconds.
    pub occlusion: Option<(f64, f64)>,
    /// A conveyor under the block; it starts in the middle of its travel at full speed
    /// ([`Conveyor::middle_time`]).
    pub conveyor: Option<Conveyor>,
    /// The tracker's feedforward, overriding the scenario's method (`None`: the method's).
    pub feedforward: Option<Feedforward>,
    /// Hand over with the target filter's velocity and feed it forward in the servo law
    /// (the "ff+target" method).
    pub target_velocity: bool,
}

impl LoopOptions {
    /// The options a scenario's method implies (no occlusion).
    pub fn for_scenario(s: &Scenario) -> Self {
        let target_velocity = s.method() == Feedforward::OnWithTarget;
        Self { occlusion: None, conveyor: None, feedforward: None, target_velocity }
    }
}

/// The servo's side of one frame (the extra columns of `trace.csv`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ServoRow {
    /// Capture time (s).
    pub t: f64,
    /// The servo's command at `t` (camera twist in `Σ_CR`).
    pub command: CameraTwist,
    /// True servo error: the true relative pose against the desired one.
    pub error: PoseError,
    /// Whether the servo was acting on an estimate of a held block at `t`.
    pub held: bool,
    /// Whether the block was hidden in this frame.
    pub occluded: bool,
    /// Largest true camera speed since the previous frame (m/s, from `q̇`).
    pub camera_speed_m_s: f64,
    /// Largest true camera angular speed since the previous frame (rad/s).
    pub camera_rot_speed_rad_s: f64,
    /// Tracker error `‖t̂ − t‖` of this frame's estimate (m).
    pub tracker_error_m: f64,
    /// Whether the block's own motion was steady (no conveyor reversal within
    /// [`STEADY_AFTER_REVERSAL_S`]).
    pub steady: bool,
}

/// Header of the servo columns of `trace.csv`.
pub const SERVO_COLUMNS: [&str; 15] = [
    "cmd_vx_m_s",
    "cmd_vy_m_s",
    "cmd_vz_m_s",
    "cmd_wx_rad_s",
    "cmd_wy_rad_s",
    "cmd_wz_rad_s",
    "servo_ex_mm",
    "servo_ey_mm",
    "servo_ez_mm",
    "servo_err_mm",
    "servo_err_deg",
    "held",
    "occluded",
    "camera_speed_m_s",
    "camera_rot_speed_rad_s",
];

impl ServoRow {
    /// The fields under [`SERVO_COLUMNS`].
    pub fn record(&self) -> Vec<String> {
        let c = &self.command;
        let mut rec: Vec<String> = c.v.iter().chain(c.w.iter()).map(|v| format!("{v:.6}")).collect();
        rec.extend(self.error.translation.iter().map(|v| format!("{:.4}", v * 1e3)));
        rec.push(format!("{:.4}", self.error.translation_norm() * 1e3));
        rec.push(format!("{:.4}", self.error.rotation_norm().to_degrees()));
        rec.push(u8::from(self.held).to_string());
        rec.push(u8::from(self.occluded).to_string());
        rec.push(format!("{:.6}", self.camera_speed_m_s));
        rec.push(format!("{:.6}", self.camera_rot_speed_rad_s));
        rec
    }
}

/// How a closed-loop run ended (the stability map's classes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// The servo error settled.
    Converged,
    /// The servo error keeps swinging (its spread over the second half exceeds
    /// [`OSCILLATION_MM`] or [`OSCILLATION_DEG`]).
    Oscillating,
    /// The servo error grows or exceeds [`DIVERGED_MM`] / [`DIVERGED_DEG`].
    Diverged,
    /// The tracker lost the block (not held outside an occlusion in the second half, or
    /// its error above [`LOST_TRACKER_M`] at the end).
    Lost,
}

impl Outcome {
    /// Lower-case name.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Converged => "converged",
            Self::Oscillating => "oscillating",
            Self::Diverged => "diverged",
            Self::Lost => "lost",
        }
    }
}

/// Spread (standard deviation) of the servo error's translation that counts as oscillating (mm).
pub const OSCILLATION_MM: f64 = 5.0;
/// Spread of the servo error's rotation that counts as oscillating (degrees).
pub const OSCILLATION_DEG: f64 = 1.0;
/// Servo error that counts as diverged (mm).
pub const DIVERGED_MM: f64 = 100.0;
/// Servo rotation error that counts as diverged (degrees).
pub const DIVERGED_DEG: f64 = 30.0;
/// Tracker error at the end that counts as a lost block (m).
pub const LOST_TRACKER_M: f64 = 0.03;

/// Summary of the servo side of a run (steady state = the frames of the second half of the run
/// whose [`ServoRow::steady`] is set).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ServoSummary {
    /// Start of the steady-state window (s).
    pub steady_from_s: f64,
    /// RMS of `‖t_e‖` over the steady-state window (mm).
    pub rms_err_mm: f64,
    /// RMS of the rotation error over the steady-state window (degrees).
    pub rms_err_deg: f64,
    /// Largest `‖t_e‖` over the steady-state window (mm).
    pub max_err_mm: f64,
    /// Standard deviation of `t_e` about its mean over the steady-state window (mm).
    pub spread_mm: f64,
    /// Standard deviation of the rotation error about its mean (degrees).
    pub spread_deg: f64,
    /// Frames in which the servo was not acting on an estimate of a held block.
    pub frames_not_held: usize,
    /// Largest true camera speed over the run (m/s).
    pub max_camera_speed_m_s: f64,
    /// Largest commanded speed over the run (m/s).
    pub max_command_speed_m_s: f64,
    /// The class of the run.
    pub outcome: Outcome,
}

fn norm(v: &Vector3<f32>) -> f64 {
    f64::from(v.norm())
}

impl ServoSummary {
    /// Summarises the servo rows of a run of `duration_s`.
    pub fn of(rows: &[ServoRow], duration_s: f64) -> Self {
        let from = 0.5 * duration_s;
        let steady: Vec<&ServoRow> = rows.iter().filter(|r| r.t >= from && r.steady).collect();
        let n = steady.len().max(1) as f64;
        let mean_t = steady.iter().fold(Vector3::<f64>::zeros(), |a, r| a + r.error.translation.cast::<f64>()) / n;
        let mean_r = steady.iter().fold(Vector3::<f64>::zeros(), |a, r| a + r.error.rotation.cast::<f64>()) / n;
        let (mut sq_t, mut sq_r, mut var_t, mut var_r, mut max_t) = (0.0, 0.0, 0.0, 0.0, 0.0f64);
        for r in &steady {
            let (et, er) = (r.error.translation.cast::<f64>(), r.error.rotation.cast::<f64>());
            sq_t += et.norm_squared();
            sq_r += er.norm_squared();
            var_t += (et - mean_t).norm_squared();
            var_r += (er - mean_r).norm_squared();
            max_t = max_t.max(et.norm());
        }
        let summary = Self {
            steady_from_s: from,
            rms_err_mm: (sq_t / n).sqrt() * 1e3,
            rms_err_deg: (sq_r / n).sqrt().to_degrees(),
            max_err_mm: max_t * 1e3,
            spread_mm: (var_t / n).sqrt() * 1e3,
            spread_deg: (var_r / n).sqrt().to_degrees(),
            frames_not_held: rows.iter().filter(|r| !r.held).count(),
            max_camera_speed_m_s: rows.iter().map(|r| r.camera_speed_m_s).fold(0.0, f64::max),
            max_command_speed_m_s: rows.iter().map(|r| norm(&r.command.v)).fold(0.0, f64::max),
            outcome: Outcome::Converged,
        };
        Self { outcome: classify(&summary, &steady), ..summary }
    }
}

fn classify(s: &ServoSummary, steady: &[&ServoRow]) -> Outcome {
    let lost_frames = steady.iter().any(|r| !r.held && !r.occluded);
    let lost_end = steady.last().is_none_or(|r| r.tracker_error_m > LOST_TRACKER_M);
    if lost_frames || lost_end {
        return Outcome::Lost;
    }
    let max_deg = steady.iter().map(|r| f64::from(r.error.rotation_norm()).to_degrees()).fold(0.0, f64::max);
    let half = steady.len() / 2;
    let rms = |rows: &[&ServoRow]| {
        (rows.iter().map(|r| f64::from(r.error.translation.norm_squared())).sum::<f64>() / rows.len().max(1) as f64)
            .sqrt()
    };
    let growing = rms(&steady[half..]) > 2.0 * rms(&steady[..half]) && rms(&steady[half..]) > 0.02;
    if s.max_err_mm > DIVERGED_MM || max_deg > DIVERGED_DEG || growing {
        Outcome::Diverged
    } else if s.spread_mm > OSCILLATION_MM || s.spread_deg > OSCILLATION_DEG {
        Outcome::Oscillating
    } else {
        Outcome::Converged
    }
}

/// An estimate on its way to the servo.
#[derive(Debug, Clone, Copy)]
struct Released {
    psi: Psi,
    q: [f32; DOF],
    filter: TargetFilter,
    held: bool,
}

/// The servo side of the 1 kHz loop: hand-over, law, setpoint integration.
struct Controller {
    servo: Servo,
    mount: Isometry3<f32>,
    mount64: Isometry3<f64>,
    setpoint: Option<Isometry3<f64>>,
    pending: VecDeque<(f64, Released)>,
    latest: Option<Released>,
    held: bool,
    target_velocity: bool,
    speed: f64,
    rot_speed: f64,
}

/// A setpoint further than this from the flange (m or rad) is re-anchored at the flange (the
/// arm could not follow: joint velocity or position limits).
const SETPOINT_ANCHOR: f64 = 0.01;

impl Controller {
    fn hand_over(&self, r: &Released, joints: &JointSample<DOF>) -> Option<ServoInput> {
        let camera = PA10.forward(&joints.q) * self.mount;
        if self.target_velocity {
            let p = r.filter.predict(&PA10, &self.mount, joints, joints.time_us).ok()?;
            let r_cw = camera.rotation.inverse();
            let target_velocity = CameraTwist { v: r_cw * p.velocity.v, w: r_cw * p.velocity.w };
            return Some(ServoInput { pose: p.psi.try_to_isometry().ok()?, target_velocity });
        }
        r.psi.validate().ok()?;
        let world = target_motion::world_pose(&PA10, &r.q, &self.mount, &r.psi);
        Some(ServoInput { pose: camera.inverse() * world, target_velocity: CameraTwist::ZERO })
    }

    fn control(&mut self, arm: &ArmSim) -> (Isometry3<f64>, Twist) {
        let now = arm.time();
        while self.pending.front().is_some_and(|(t, _)| *t <= now + 1e-6) {
            if let Some((_, r)) = self.pending.pop_front() {
                self.held = r.held;
                self.latest = Some(r);
            }
        }
        let joints = arm.joint_sample();
        let input = if self.held { self.latest.as_ref().and_then(|r| self.hand_over(r, &joints)) } else { None };
        let dt = CONTROL_PERIOD_S as f32;
        let out = match self.servo.update(input.as_ref(), dt) {
            Ok(o) => o.command,
            Err(e) => {
                log::warn!("servo input refused at t = {now:.3}: {e}");
                self.servo.update(None, dt).map_or(CameraTwist::ZERO, |o| o.command)
            }
        };
        let actual = feedforward::camera_twist(&PA10, &joints.q, &joints.qd, &self.mount);
        self.speed = self.speed.max(norm(&actual.v));
        self.rot_speed = self.rot_speed.max(norm(&actual.w));

        let flange = arm.flange_pose();
        let mut sp = self.setpoint.unwrap_or(flange);
        let e = arm.flange_error(&sp);
        if e.position_norm() > SETPOINT_ANCHOR || e.rotation_norm() > SETPOINT_ANCHOR {
            sp = flange;
        }
        let r_wc = (sp * self.mount64).rotation;
        let w = r_wc * out.w.cast::<f64>();
        let v_cam = r_wc * out.v.cast::<f64>();
        let v = v_cam - w.cross(&(sp.rotation * self.mount64.translation.vector));
        let h = CONTROL_PERIOD_S;
        sp.translation.vector += v * h;
        sp.rotation = UnitQuaternion::from_scaled_axis(w * h) * sp.rotation;
        self.setpoint = Some(sp);
        (sp, Twist { v, w })
    }
}

/// The servo configuration of a scenario's `[servo]`; `relative0` is `^CR T_M` at `t = 0`
/// (the default desired orientation).
pub fn servo_config(sec: &ServoSection, relative0: &Isometry3<f64>) -> ServoConfig {
    let rotation = match sec.desired_q_xyzw {
        Some([x, y, z, w]) => UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z)),
        None => relative0.rotation,
    };
    let [x, y, z] = sec.desired_t_m;
    ServoConfig {
        desired: Isometry3::from_parts(Translation3::new(x, y, z), rotation).cast::<f32>(),
        gain: sec.gain as f32,
        limits: ServoLimits {
            max_speed_m_s: sec.max_speed_m_s as f32,
            max_rot_speed_rad_s: sec.max_rot_speed_rad_s as f32,
            max_accel_m_s2: sec.max_accel_m_s2 as f32,
            max_rot_accel_rad_s2: sec.max_rot_accel_rad_s2 as f32,
        },
    }
}

/// The outcome of a closed-loop run.
#[derive(Debug, Clone)]
pub struct ClosedLoopOutput {
    /// The trace and summary, as an open-loop run has them.
    pub run: RunOutput,
    /// The servo's side of every frame.
    pub servo: Vec<ServoRow>,
    /// Its summary.
    pub servo_summary: ServoSummary,
}

/// `summary.json` of a closed-loop run.
#[derive(Debug, Clone, Serialize)]
pub struct ClosedLoopSummary<'a> {
    /// The tracker's summary.
    #[serde(flatten)]
    pub run: &'a Summary,
    /// The servo's.
    pub servo: &'a ServoSummary,
}

/// Runs a scenario with `[servo]` in closed loop with the host's tracker (see the module
/// documentation). `on_frame` is called after every frame.
///
/// # Errors
/// No `[servo]` section, or the world, tracker or servo cannot be built.
pub fn run(s: &Scenario, opts: &LoopOptions, on_frame: impl FnMut()) -> Result<ClosedLoopOutput> {
    let mut board = ServoBoard::closed_loop(s, opts)?;
    let (tracker, rejected) = run_host_tracker(s, &mut board, on_frame)?;
    let mut out = board.finish(rejected);
    out.run.summary.edge_shift_px = Some(tracker.edge_shift_px());
    Ok(out)
}

/// Drives `board` to its end with the host's tracker (the core's `board::run`); returns the
/// tracker and the frames it refused.
fn run_host_tracker(s: &Scenario, board: &mut ServoBoard, mut on_frame: impl FnMut()) -> Result<(SimTracker, u32)> {
    let mut s = *s;
    s.tracker.0.feedforward = board.feedforward();
    let mut tracker: SimTracker = experiment::scenario_tracker(&s, Population::Around(board.start_pose()))?;
    let n = crate::sim::board::image_bytes(&s);
    let (mut left, mut right) = (vec![0u8; n], vec![0u8; n]);
    let mut progress = ProgressBoard { inner: board, on_frame: &mut on_frame };
    let stats = evorec_core::board::run(&mut progress, &mut tracker, &mut left, &mut right, u32::MAX)
        .map_err(|e| anyhow!("closed loop: {e:?}"))?;
    Ok((tracker, stats.rejected))
}

/// The visual servo as the arm controller of a [`SimBoard`]: the closed loop as the
/// camera-controller board a tracker sees ([`ServoBoard`]), the same board for the host's
/// tracker ([`run`], through the core's `board::run`) and for the firmware's on QEMU
/// (`crate::firmware::hil::run_closed_loop`, over the link), so both close the loop with the same code.
///
/// Before each frame it runs the 1 kHz servo loop up to the frame's capture time (the board
/// then renders the frame pair as the cameras' RGB565 pixels, the bytes the firmware receives
/// too); a published estimate is queued until it reaches the servo, and the frame's servo row
/// recorded. The "ff+target" hand-over predicts with the controller's own copy of the core's
/// [`TargetFilter`], fed as the tracker feeds its own ([`TargetFilter::update_from_estimate`]
/// on [`Estimate::target_measurement`]: the same code on the same numbers, only with
/// [`Feedforward::OnWithTarget`]), because the firmware publishes the estimate only.
pub struct ServoLoop {
    ctl: Controller,
    filter: TargetFilter,
    feedforward: Feedforward,
    opts: LoopOptions,
    desired: Isometry3<f32>,
    delay_s: f64,
    /// Whether the block's own motion is steady in the frame delivered last.
    steady: bool,
    rows: Vec<ServoRow>,
}

/// The closed loop of a `[servo]` scenario as the board a tracker sees.
pub type ServoBoard = SimBoard<ServoLoop>;

impl ServoLoop {
    /// The servo of `s` (which needs a `[servo]` section) with `opts`, for `world` at `t = 0`.
    ///
    /// # Errors
    /// No `[servo]` section, or the servo or the target filter cannot be built.
    pub fn new(s: &Scenario, opts: &LoopOptions, world: &World) -> Result<Self> {
        let sec = s.servo.ok_or_else(|| anyhow!("the scenario has no [servo] section"))?;
        let config = servo_config(&sec, &world.target_in_camera());
        let desired = config.desired;
        let servo = Servo::new(config).map_err(|e| anyhow!("servo: {e}"))?;
        let ctl = Controller {
            servo,
            mount: crate::sim::board::flange_to_camera(s),
            mount64: flange_to_camera_f64(s.camera.baseline_m),
            setpoint: None,
            pending: VecDeque::new(),
            latest: None,
            held: false,
            target_velocity: opts.target_velocity,
            speed: 0.0,
            rot_speed: 0.0,
        };
        Ok(Self {
            ctl,
            filter: crate::sim::board::target_filter(s)?,
            feedforward: opts.feedforward.unwrap_or(s.tuning().feedforward),
            opts: *opts,
            desired,
            delay_s: f64::from(sec.delay_frames) * s.frame_period_s,
            steady: true,
            rows: Vec::with_capacity(frame_total(s) as usize),
        })
    }
}

impl ArmController for ServoLoop {
    fn advance(&mut self, world: &mut World, t: f64) -> bool {
        let ctl = &mut self.ctl;
        world.advance_with(t, |arm| ctl.control(arm));
        self.steady = self.opts.conveyor.is_none() || world.target_path().steady_for(t) >= STEADY_AFTER_REVERSAL_S;
        let occluded = self.opts.occlusion.is_some_and(|(a, d)| t >= a && t < a + d);
        world.set_target_hidden(occluded);
        occluded
    }

    fn publish(&mut self, world: &World, capture: &Capture, est: &Estimate) -> Option<Handover> {
        let Capture { t, truth, joints, hidden } = *capture;
        let feedforward = self.filter.feedforward_velocity();
        if self.feedforward == Feedforward::OnWithTarget {
            let measured = &est.target_measurement;
            self.filter.update_from_estimate(&PA10, &self.ctl.mount, &joints, measured, est.status);
        }
        let held = est.status.holds();
        let released = Released { psi: est.psi, q: joints.q, filter: self.filter, held };
        self.ctl.pending.push_back((t + self.delay_s, released));
        let true_rel: Isometry3<f32> = world.target_in_camera().cast();
        self.rows.push(ServoRow {
            t,
            command: *self.ctl.servo.command(),
            error: PoseError::between(&true_rel, &self.desired),
            held: self.ctl.held,
            occluded: hidden,
            camera_speed_m_s: std::mem::take(&mut self.ctl.speed),
            camera_rot_speed_rad_s: std::mem::take(&mut self.ctl.rot_speed),
            tracker_error_m: norm(&(est.psi.translation() - truth.translation())),
            steady: self.steady,
        });
        // The velocities the servo is handed at the release time; the poses there depend on
        // the arm's motion until then, which the servo has not yet run.
        Some(Handover {
            t_out: t + self.delay_s,
            poses: None,
            trusted: self.filter.is_trusted(),
            velocity: self.filter.feedforward_velocity(),
            feedforward,
            true_velocity: world.target_velocity(),
        })
    }
}

impl ServoBoard {
    /// The closed loop of `s` (which needs a `[servo]` section) with `opts`, at `t = 0`; the
    /// tracker's population starts around the truth before `opts`' conveyor moves the block.
    ///
    /// # Errors
    /// No `[servo]` section, or the world or servo cannot be built.
    pub fn closed_loop(s: &Scenario, opts: &LoopOptions) -> Result<Self> {
        let world = World::new(s)?;
        let arm = ServoLoop::new(s, opts, &world)?;
        let mut board = SimBoard::with_arm(world, arm);
        if let Some(conveyor) = opts.conveyor {
            board.world_mut().set_target_path(TargetPath::Conveyor { conveyor, start_s: conveyor.middle_time() });
        }
        Ok(board)
    }

    /// The tracker's feedforward in this loop.
    pub fn feedforward(&self) -> Feedforward {
        self.arm().feedforward
    }

    /// The servo's copy of the target filter.
    pub fn target_filter(&self) -> &TargetFilter {
        &self.arm().filter
    }

    /// The run's output; `rejected` frames were refused by the tracker.
    pub fn finish(self, rejected: u32) -> ClosedLoopOutput {
        let s = *self.world().scenario();
        let (rows, arm) = self.into_parts();
        let summary = Summary::of(&rows, rejected, &s);
        let servo_summary = ServoSummary::of(&arm.rows, s.duration_s);
        ClosedLoopOutput { run: RunOutput { rows, summary }, servo: arm.rows, servo_summary }
    }
}

/// Writes `trace.csv` (with the servo columns), `summary.json` (with the servo summary) and
/// the plots of a closed-loop run into `dir`.
///
/// # Errors
/// I/O errors.
pub fn write_outputs(out: &ClosedLoopOutput, dir: &std::path::Path, title: &str) -> Result<()> {
    std::fs::create_dir_all(dir)?;
    let trace = dir.join("trace.csv");
    let extra: Vec<Vec<String>> = out.servo.iter().map(ServoRow::record).collect();
    crate::output::io::write_trace_with(&trace, &out.run.rows, &SERVO_COLUMNS, &extra)?;
    let summary = ClosedLoopSummary { run: &out.run.summary, servo: &out.servo_summary };
    crate::output::io::write_json(&dir.join("summary.json"), &summary)?;
    crate::output::io::write_tracker_config(dir, out.run.summary.scenario.tuning())?;
    crate::output::plot::plot_trace(&trace, dir, title)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use evorec_core::tuning::Feedforward;

    /// A still block, the camera brought 0.1 m closer, 320×240.
    pub(super) fn scenario(duration_s: f64) -> Scenario {
        let mut s = Scenario::new(1, duration_s, Feedforward::On);
        s.camera.width = 320;
        s.camera.height = 240;
        s.camera.fx = 400.0;
        s.camera.fy = 400.0;
        s.camera.cx = 160.0;
        s.camera.cy = 120.0;
        s.camera.supersample = 1;
        s.target.omega_rad_s = 0.0;
        s.servo = Some(ServoSection::new([-0.05, 0.0, 0.6]));
        s
    }

    #[test]
    fn converges_on_a_still_block_within_the_speed_limit() {
        let s = scenario(6.0);
        let out = run(&s, &LoopOptions::for_scenario(&s), || {}).unwrap_or_else(|e| unreachable!("{e}"));
        let sum = out.servo_summary;
        assert_eq!(sum.outcome, Outcome::Converged, "{sum:?}");
        assert!(sum.rms_err_mm < 5.0 && sum.rms_err_deg < 1.0, "{sum:?}");
        let first = out.servo[0].error.translation_norm();
        assert!((first - 0.1).abs() < 1e-3, "starts 0.1 m from the desired pose: {first}");
        let limit = ServoSection::new([0.0; 3]).max_speed_m_s;
        assert!(sum.max_camera_speed_m_s <= limit * 1.02, "{sum:?}");
    }

    #[test]
    fn the_boards_target_filter_is_the_trackers() {
        let mut s = scenario(2.0);
        s.set_method(Feedforward::OnWithTarget);
        let mut board =
            ServoBoard::closed_loop(&s, &LoopOptions::for_scenario(&s)).unwrap_or_else(|e| unreachable!("{e}"));
        let (tracker, rejected) = run_host_tracker(&s, &mut board, || {}).unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(rejected, 0);
        assert!(tracker.target_filter().has_track() && tracker.target_filter().is_trusted());
        assert_eq!(board.target_filter(), tracker.target_filter());
    }

    #[test]
    fn the_trace_of_a_closed_loop_holds_the_velocities_handed_to_the_servo() {
        let mut s = scenario(2.0);
        s.set_method(Feedforward::OnWithTarget);
        let out = run(&s, &LoopOptions::for_scenario(&s), || {}).unwrap_or_else(|e| unreachable!("{e}"));
        let rows = &out.run.rows;
        let handed: Vec<&Handover> = rows.iter().filter_map(|r| r.handover.as_ref()).collect();
        assert_eq!(handed.len(), rows.len(), "every frame records its hand-over");
        for (r, h) in rows.iter().zip(&handed) {
            assert!((h.t_out - (r.t + s.frame_period_s)).abs() < 1e-9, "released one frame after capture");
            assert_eq!(h.poses, None, "the poses at the release time are not known at publication");
            assert_eq!((h.true_velocity.v.norm(), h.true_velocity.w.norm()), (0.0, 0.0), "a still block");
        }
        // Once the filter has observed the block, the servo is handed its (small, non-zero) velocity.
        let last = handed[handed.len() - 1];
        assert!(last.trusted);
        assert!(last.velocity.v.norm() > 0.0 && last.velocity.v.norm() < 0.05, "{:?}", last.velocity);
        assert_eq!(last.feedforward, handed[handed.len() - 2].velocity);
    }

    #[test]
    fn a_tuned_target_filter_reaches_the_tracker_and_the_boards_copy() {
        let mut s = scenario(2.0);
        s.set_method(Feedforward::OnWithTarget);
        let default_run = {
            let mut board =
                ServoBoard::closed_loop(&s, &LoopOptions::for_scenario(&s)).unwrap_or_else(|e| unreachable!("{e}"));
            run_host_tracker(&s, &mut board, || {}).unwrap_or_else(|e| unreachable!("{e}")).0
        };
        // A slower block and noisier estimates than the defaults say.
        s.tracker.0.target.acceleration_m_s2 = 0.2;
        s.tracker.0.target.image_noise_px = 2.0;
        let mut board =
            ServoBoard::closed_loop(&s, &LoopOptions::for_scenario(&s)).unwrap_or_else(|e| unreachable!("{e}"));
        let (tracker, _) = run_host_tracker(&s, &mut board, || {}).unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(tracker.target_filter().params(), &s.tuning().target);
        assert_eq!(board.target_filter(), tracker.target_filter());
        assert_ne!(tracker.target_filter(), default_run.target_filter());
    }

    #[test]
    fn occlusion_stops_the_arm_within_its_limits_and_the_loop_recovers() {
        let s = scenario(6.0);
        let sec = s.servo.unwrap_or_else(|| unreachable!());
        let (start, duration) = (0.6, 1.0);
        let opts = LoopOptions { occlusion: Some((start, duration)), ..LoopOptions::for_scenario(&s) };
        let out = run(&s, &opts, || {}).unwrap_or_else(|e| unreachable!("{e}"));
        let rows = &out.servo;
        // Moving towards the block when the occluder comes.
        let before = rows.iter().filter(|r| r.t < start).map(|r| r.camera_speed_m_s).fold(0.0, f64::max);
        assert!(before > 0.05, "{before}");
        // Stopped within: one frame for the gate + the delay + max_speed / max_accel (+ a frame).
        let stop_by =
            start + (2.0 + f64::from(sec.delay_frames)) * s.frame_period_s + sec.max_speed_m_s / sec.max_accel_m_s2;
        for r in rows.iter().filter(|r| r.t > stop_by && r.t < start + duration) {
            assert!(r.camera_speed_m_s < 1e-3, "still moving at t = {}: {} m/s", r.t, r.camera_speed_m_s);
            assert!(!r.held);
        }
        // Never above the speed limit, also when it resumes.
        for r in rows {
            assert!(r.camera_speed_m_s <= sec.max_speed_m_s * 1.02, "t = {}: {} m/s", r.t, r.camera_speed_m_s);
        }
        // Tracking again within 0.5 s of reappearance, and converged at the end.
        let back = rows.iter().find(|r| r.t >= start + duration && r.held).map(|r| r.t);
        assert!(back.is_some_and(|t| t < start + duration + 0.5), "{back:?}");
        let last = rows.last().map(|r| r.error.translation_norm()).unwrap_or(1.0);
        assert!(last < 0.005, "{last}");
        let stopped = rows.iter().find(|r| r.t > start && r.camera_speed_m_s < 1e-3).map(|r| r.t - start);
        let after = rows.iter().filter(|r| r.t >= start + duration).map(|r| r.camera_speed_m_s).fold(0.0, f64::max);
        println!(
            "occlusion: speed before {before:.3} m/s, stopped {stopped:?} s after it began, tracking again at {back:?} s, \
             max speed after {after:.3} m/s (limit {}), final error {:.2} mm",
            sec.max_speed_m_s,
            last * 1e3
        );
    }
}
