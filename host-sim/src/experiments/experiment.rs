//! One run of a scenario: the simulated board drives the core's tracker through the core's
//! generic loop, exactly as the firmware does; the result is a trace and its summary
//! (paper eq. 40–41).

use std::path::Path;

use anyhow::{Context, Result};
use evorec_core::board;
use evorec_core::limits::{DEFAULT_GRID, PA10_DOF};
use evorec_core::pose::Psi;
use evorec_core::status::Status;
use evorec_core::tracker::{ConfigError, StepError, Tracker, TrackerConfig};
use serde::Serialize;

use crate::experiments::truth::{self as eval, WrongTracking};
pub use crate::experiments::truth::{Rms, RotationError, isometry_of, rms_columns};
use crate::sim::board::{self as sim, HandedPoses, Handover, SimBoard, TraceRow, World};
use crate::sim::occlusion::Initial;
use crate::sim::scenario::{HOST_POPULATION_CAPACITY, Scenario};

/// The tracker the simulator runs: PA-10, the default population capacity (the size in use is
/// the scenario's `[tracker] ga.population`) and sample rows.
pub type SimTracker = Tracker<PA10_DOF, HOST_POPULATION_CAPACITY, DEFAULT_GRID>;

/// Half-widths of the initial population around the known true pose at `t = 0` (the paper
/// starts "with known initial target's pose"): 2 mm and 0.004 in ε.
pub const INITIAL_SPREAD: [f32; 6] = [0.002, 0.002, 0.002, 0.004, 0.004, 0.004];

/// The tracker configuration of a scenario.
///
/// # Errors
/// Invalid camera settings.
pub fn tracker_config(s: &Scenario) -> Result<TrackerConfig<PA10_DOF>> {
    Ok(TrackerConfig::pa10(sim::rig(s)?, sim::block(s), sim::flange_to_camera(s), sim::search_space())
        .with_seed(s.seed)
        .with_tuning(*s.tuning()))
}

/// How a new tracker's population starts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Population {
    /// Around a known pose, within [`INITIAL_SPREAD`] ([`Tracker::reset_around`]); the
    /// tracker starts tracking.
    Around(Psi),
    /// Uniform over the search space, as [`Tracker::new`] draws it; the tracker starts
    /// searching.
    Uniform,
    /// Uniform, drawn once more from the tracker's generator ([`Tracker::reset_uniform`] after
    /// [`Tracker::new`]): the start of `evorec track` without an initial pose (for one seed, a
    /// different population from [`Population::Uniform`]'s).
    Redrawn,
}

/// Why a tracker could not be set up ([`setup_tracker`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SetupError {
    /// The configuration ([`Tracker::new`]).
    Config(ConfigError),
    /// The initial pose ([`Tracker::reset_around`]).
    InitialPose(StepError),
}

impl core::fmt::Display for SetupError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Config(e) => write!(f, "tracker: {e}"),
            Self::InitialPose(e) => write!(f, "initial pose: {e}"),
        }
    }
}

impl std::error::Error for SetupError {}

/// The one set-up of a host tracker: built from `config` (its tuning included), its population
/// started as `population`. (The firmware's counterpart, which builds the
/// tracker in place, is `evorec_firmware::setup::Setup::build_tracker_in`.)
///
/// # Errors
/// [`SetupError`].
pub fn setup_tracker<const DOF: usize, const P: usize, const G: usize>(
    config: TrackerConfig<DOF>,
    population: Population,
) -> Result<Tracker<DOF, P, G>, SetupError> {
    let mut tracker = Tracker::new(config).map_err(SetupError::Config)?;
    match population {
        Population::Around(psi) => tracker.reset_around(&psi, &INITIAL_SPREAD).map_err(SetupError::InitialPose)?,
        Population::Uniform => {}
        Population::Redrawn => tracker.reset_uniform(),
    }
    Ok(tracker)
}

/// The tracker of a scenario ([`tracker_config`], tuned by its `[tracker]` table) with `G`
/// points per sample row, its population started as `population` ([`setup_tracker`]).
///
/// # Errors
/// Invalid camera settings, or as [`setup_tracker`].
pub fn scenario_tracker<const G: usize>(
    s: &Scenario,
    population: Population,
) -> Result<Tracker<PA10_DOF, HOST_POPULATION_CAPACITY, G>> {
    Ok(setup_tracker(tracker_config(s)?, population)?)
}

/// Accuracy of a run (paper eq. 40–41): mean fitness and RMS errors over all frames.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Accuracy {
    /// Mean fitness `F̄`.
    #[serde(rename = "F_mean")]
    pub f_mean: f64,
    /// RMS errors of the estimates (flattened: `rms_x_mm` … `rms_e3`, `frames`).
    #[serde(flatten)]
    pub rms: Rms,
}

impl Accuracy {
    /// Computes the summary of a trace.
    pub fn of(rows: &[TraceRow]) -> Self {
        let n = rows.len().max(1) as f64;
        let f = rows.iter().map(|r| f64::from(r.fitness)).sum::<f64>();
        Self { f_mean: f / n, rms: pose_rms(rows.iter().map(|r| (r.estimate, r.truth))) }
    }
}

/// The RMS of `estimate − truth` over the `(estimate, truth)` pairs ([`Rms::ZERO`] for none).
fn pose_rms(pairs: impl Iterator<Item = (Psi, Psi)>) -> Rms {
    Rms::of_differences(pairs.map(|(e, t)| std::array::from_fn(|k| f64::from(e.0[k]) - f64::from(t.0[k]))))
        .unwrap_or(Rms::ZERO)
}

/// How the tracker's status went over a run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Default)]
pub struct StatusCounts {
    /// Frames reported as searching.
    pub searching: usize,
    /// Frames reported as tracking.
    pub tracking: usize,
    /// Frames reported as lost.
    pub lost: usize,
    /// Frames reported as uncertain (the block held, its pose not confirmed).
    pub uncertain: usize,
    /// Frames in which the block was hidden (occluded or removed).
    pub hidden: usize,
    /// Hidden frames reported as tracking.
    pub tracking_while_hidden: usize,
    /// Capture time of the first frame reported as tracking (s), if any.
    pub first_tracking_s: Option<f64>,
}

impl StatusCounts {
    /// Counts the statuses of a trace.
    pub fn of(rows: &[TraceRow]) -> Self {
        let mut c = Self::default();
        for r in rows {
            match r.status {
                Status::Searching => c.searching += 1,
                Status::Tracking => c.tracking += 1,
                Status::Lost => c.lost += 1,
                Status::Uncertain => c.uncertain += 1,
            }
            c.hidden += usize::from(r.hidden);
            c.tracking_while_hidden += usize::from(r.hidden && r.status == Status::Tracking);
            if c.first_tracking_s.is_none() && r.status == Status::Tracking {
                c.first_tracking_s = Some(r.t);
            }
        }
        c
    }
}

/// A simulated run's rotation error.
impl RotationError {
    /// Of a simulated run: each frame's estimate against its true pose (no symmetry: as the
    /// run's other errors).
    pub fn of_run(rows: &[TraceRow]) -> Option<Self> {
        let angle = |r: &TraceRow| isometry_of(&r.estimate).rotation.angle_to(&isometry_of(&r.truth).rotation);
        Self::of(rows.iter().map(|r| angle(r).to_degrees()))
    }
}

/// How `summary.json` writes an RMS of the hand-over: per axis as `[x, y, z]` (mm) and
/// `[ε₁, ε₂, ε₃]`, and the lengths of both.
fn serialize_handover_rms<S: serde::Serializer>(r: &Rms, s: S) -> std::result::Result<S::Ok, S::Error> {
    use serde::ser::SerializeStruct;
    let mut st = s.serialize_struct("Rms", 4)?;
    st.serialize_field("rms_xyz_mm", &[r.rms_x_mm, r.rms_y_mm, r.rms_z_mm])?;
    st.serialize_field("rms_eps", &[r.rms_e1, r.rms_e2, r.rms_e3])?;
    st.serialize_field("rms_position_mm", &r.position_mm())?;
    st.serialize_field("rms_eps_norm", &r.eps_norm())?;
    st.end()
}

/// The hand-over at the output time (`[start] delay_s` after capture), over the frames
/// reported as tracking (the others carry no measurement to hand over).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct HandoverSummary {
    /// The delay (s).
    pub delay_s: f64,
    /// Frames counted.
    pub frames: usize,
    /// The estimate against the truth at capture time (the tracker's own error).
    #[serde(serialize_with = "serialize_handover_rms")]
    pub at_capture: Rms,
    /// The estimate held unchanged until the output time, against the truth then.
    #[serde(serialize_with = "serialize_handover_rms")]
    pub held: Rms,
    /// The core's prediction for the output time against the truth then.
    #[serde(serialize_with = "serialize_handover_rms")]
    pub predicted: Rms,
    /// `predicted.position_mm() / at_capture.position_mm()`.
    pub position_ratio: f64,
    /// `predicted.eps_norm() / at_capture.eps_norm()`.
    pub eps_ratio: f64,
    /// Fraction of the frames whose prediction used a trusted target velocity.
    pub trusted_fraction: f64,
    /// Frames (of all, tracked or not) to which "ff+target" feeds a non-zero target velocity
    /// forward ([`Handover::feedforward`]; in the other methods, what it would have fed). In a
    /// "ff+target" run, 0 means the run is identical to "ff".
    pub target_feedforward_frames: usize,
    /// RMS error of the target velocity used (m/s), over the trusted frames.
    pub rms_velocity_error_m_s: f64,
    /// RMS error of the angular velocity used (rad/s), over the trusted frames.
    pub rms_rate_error_rad_s: f64,
}

impl HandoverSummary {
    /// The summary of a trace's hand-over (`None` without hand-over rows).
    pub fn of(rows: &[TraceRow], delay_s: f64) -> Option<Self> {
        let still = |v: &evorec_core::target_motion::TargetVelocity| v.v.norm() == 0.0 && v.w.norm() == 0.0;
        let target_feedforward_frames =
            rows.iter().filter(|r| r.handover.as_ref().is_some_and(|h| !still(&h.feedforward))).count();
        let rows: Vec<(&TraceRow, &Handover, HandedPoses)> = rows
            .iter()
            .filter(|r| r.status == Status::Tracking)
            .filter_map(|r| r.handover.as_ref().and_then(|h| h.poses.map(|p| (r, h, p))))
            .collect();
        if rows.is_empty() {
            return None;
        }
        let at_capture = pose_rms(rows.iter().map(|(r, _, _)| (r.estimate, r.truth)));
        let held = pose_rms(rows.iter().map(|(r, _, p)| (r.estimate, p.truth_out)));
        let predicted = pose_rms(rows.iter().map(|(_, _, p)| (p.predicted, p.truth_out)));
        let trusted: Vec<&Handover> = rows.iter().map(|(_, h, _)| *h).filter(|h| h.trusted).collect();
        let vel = rms_columns::<2>(trusted.iter().map(|h| {
            let (dv, dw) = (h.velocity.v - h.true_velocity.v, h.velocity.w - h.true_velocity.w);
            [f64::from(dv.norm()), f64::from(dw.norm())]
        }))
        .unwrap_or([0.0; 2]);
        let ratio = |a: f64, b: f64| if b > 0.0 { a / b } else { 0.0 };
        Some(Self {
            delay_s,
            frames: rows.len(),
            at_capture,
            held,
            predicted,
            position_ratio: ratio(predicted.position_mm(), at_capture.position_mm()),
            eps_ratio: ratio(predicted.eps_norm(), at_capture.eps_norm()),
            trusted_fraction: trusted.len() as f64 / rows.len() as f64,
            target_feedforward_frames,
            rms_velocity_error_m_s: vel[0],
            rms_rate_error_rad_s: vel[1],
        })
    }
}

/// `summary.json`.
#[derive(Debug, Clone, Serialize)]
pub struct Summary {
    /// The accuracy figures, flattened into the top level.
    #[serde(flatten)]
    pub accuracy: Accuracy,
    /// The rotation error (as `evorec track`'s), flattened into the top level (absent for no
    /// frames).
    #[serde(flatten)]
    pub rotation: Option<RotationError>,
    /// Frames per tracker status.
    pub status: StatusCounts,
    /// How often `tracking` was wrong (flattened into the top level).
    #[serde(flatten)]
    pub wrong_tracking: WrongTracking,
    /// Frames refused by the tracker (should be 0).
    pub rejected: u32,
    /// The shift of the silhouette rows the tracker learnt by the last frame, pixel widths
    /// outwards (`evorec_core::edge`); absent where the tracker ran on the firmware (`evorec
    /// hil`), whose link does not report it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub edge_shift_px: Option<f32>,
    /// The hand-over at the output time (`None` where not simulated).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub handover: Option<HandoverSummary>,
    /// The scenario, echoed.
    pub scenario: Scenario,
    /// Version of the simulator that produced the run.
    pub evorec_version: &'static str,
}

impl Summary {
    /// The summary of a run's trace.
    pub fn of(rows: &[TraceRow], rejected: u32, scenario: &Scenario) -> Self {
        Self {
            accuracy: Accuracy::of(rows),
            rotation: RotationError::of_run(rows),
            status: StatusCounts::of(rows),
            wrong_tracking: wrong_tracking(rows, &scenario.target.face_hues_deg),
            rejected,
            edge_shift_px: None,
            handover: HandoverSummary::of(rows, scenario.start.delay_s),
            scenario: *scenario,
            evorec_version: env!("CARGO_PKG_VERSION"),
        }
    }
}

/// How often a run's `tracking` was wrong: each frame's estimate against its true pose by the
/// sequence tracker's rule ([`crate::experiments::truth::FrameError::within`], modulo the colour
/// symmetry of the face hues `face_hues_deg`).
pub fn wrong_tracking(rows: &[TraceRow], face_hues_deg: &[f64; 6]) -> WrongTracking {
    let syms = eval::colour_symmetries(&face_hues_deg.map(|h| h as f32));
    WrongTracking::of(rows.iter().map(|r| {
        let (e, _) = eval::frame_error(&r.estimate, &isometry_of(&r.truth), &syms);
        (r.status, e.within())
    }))
}

/// The outcome of a run.
#[derive(Debug, Clone)]
pub struct RunOutput {
    /// One row per frame.
    pub rows: Vec<TraceRow>,
    /// The summary.
    pub summary: Summary,
}

/// Runs a scenario through the simulated board. `on_frame` is called after every frame (for
/// progress bars).
///
/// # Errors
/// If the world or the tracker cannot be built.
pub fn run(s: &Scenario, on_frame: impl FnMut()) -> Result<RunOutput> {
    run_with_rows::<DEFAULT_GRID>(s, on_frame)
}

/// [`run`] with rows of `G` points per sample row (the default tracker uses
/// [`DEFAULT_GRID`]).
///
/// # Errors
/// As [`run`].
pub fn run_with_rows<const G: usize>(s: &Scenario, mut on_frame: impl FnMut()) -> Result<RunOutput> {
    let board = SimBoard::new(World::new(s)?)?;
    let population = match s.start.initial {
        Initial::Truth => Population::Around(board.start_pose()),
        Initial::Unknown => Population::Uniform,
    };
    let mut tracker = scenario_tracker::<G>(s, population)?;
    let mut board = ProgressBoard { inner: board, on_frame: &mut on_frame };
    let n = sim::image_bytes(s);
    let (mut left, mut right) = (vec![0u8; n], vec![0u8; n]);
    let stats = board::run(&mut board, &mut tracker, &mut left, &mut right, u32::MAX)
        .map_err(|e| anyhow::anyhow!("simulated board: {e:?}"))?;
    let rows = board.inner.into_rows();
    let summary = Summary { edge_shift_px: Some(tracker.edge_shift_px()), ..Summary::of(&rows, stats.rejected, s) };
    Ok(RunOutput { rows, summary })
}

/// Wraps a board to report each delivered frame.
pub(crate) struct ProgressBoard<'a, B, F: FnMut()> {
    /// The board.
    pub(crate) inner: B,
    /// Called after every delivered frame.
    pub(crate) on_frame: &'a mut F,
}

impl<B: board::ErrorType, F: FnMut()> board::ErrorType for ProgressBoard<'_, B, F> {
    type Error = B::Error;
}

impl<B: board::CameraController<PA10_DOF>, F: FnMut()> board::CameraController<PA10_DOF> for ProgressBoard<'_, B, F> {
    type Format = B::Format;
    fn next_frame(&mut self, left: &mut [u8], right: &mut [u8]) -> Result<board::FrameInfo, B::Error> {
        let r = self.inner.next_frame(left, right);
        if r.is_ok() {
            (self.on_frame)();
        }
        r
    }
    fn joint_sample(&mut self) -> Result<evorec_core::JointSample<PA10_DOF>, B::Error> {
        self.inner.joint_sample()
    }
    fn publish(&mut self, frame: &board::FrameInfo, estimate: &evorec_core::Estimate) -> Result<(), B::Error> {
        self.inner.publish(frame, estimate)
    }
}

/// Writes `trace.csv`, `estimate.tum`, `summary.json`, `config.toml` (the tuning) and the plots
/// of a run into `dir`.
///
/// # Errors
/// I/O errors.
pub fn write_outputs(out: &RunOutput, dir: &Path, title: &str) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let trace = dir.join("trace.csv");
    crate::output::io::write_trace(&trace, &out.rows)?;
    write_estimate(out, dir)?;
    crate::output::io::write_json(&dir.join("summary.json"), &out.summary)?;
    crate::output::io::write_tracker_config(dir, out.summary.scenario.tuning())?;
    crate::output::plot::plot_trace(&trace, dir, title)?;
    Ok(())
}

/// Writes the run's estimates as `estimate.tum` into `dir` (capture time, `^CR T_M`).
///
/// # Errors
/// I/O errors.
pub fn write_estimate(out: &RunOutput, dir: &Path) -> Result<()> {
    let poses: Vec<_> = out.rows.iter().map(|r| (r.t, isometry_of(&r.estimate))).collect();
    crate::output::io::write_estimate_tum(dir, &poses, crate::output::io::TumTimes::Plain)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use evorec_core::limits::EDGE_SHIFT_RANGE_PX;
    use evorec_core::tuning::Feedforward;

    #[test]
    fn a_host_run_states_the_learnt_shift_and_a_summary_without_it_omits_the_field() {
        let s = Scenario::small(3, 1.0, Feedforward::On);
        let out = run(&s, || {}).unwrap_or_else(|e| unreachable!("{e}"));
        let px = out.summary.edge_shift_px.unwrap_or_else(|| unreachable!("a host run knows its tracker"));
        assert!((EDGE_SHIFT_RANGE_PX[0]..=EDGE_SHIFT_RANGE_PX[1]).contains(&px), "{px}");
        let json = serde_json::to_value(&out.summary).unwrap_or_else(|e| unreachable!("{e}"));
        assert_eq!(json["edge_shift_px"].as_f64(), Some(f64::from(px)));
        // As `evorec hil` writes it: the firmware does not report the shift.
        let board = Summary::of(&out.rows, 0, &s);
        let json = serde_json::to_value(&board).unwrap_or_else(|e| unreachable!("{e}"));
        assert!(json.get("edge_shift_px").is_none(), "{json}");
    }
}
