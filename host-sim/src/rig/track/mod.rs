//! `evorec track`: the tracker on a recorded sequence (`evorec-seq/1`).
//!
//! The sequence is a camera-controller board ([`board::SequenceBoard`]) driven by the core's
//! `board::run`, the same loop as the simulator's and the firmware's. A reader thread decodes
//! the PNGs ahead of the tracker. The tracker is built from the sequence: the rig from the
//! calibration, the arm from the URDF chain (any number of joints the dispatch in [`run`]
//! lists), the hand-eye transform from `flange_to_right`, the block from `[target]`, the search
//! space from `[search]` (else [`crate::sim::board::search_space`]). With an `initial_pose`
//! the population starts around it as `evorec run` starts around the truth.
//!
//! Nothing is written before the input is known good: all metadata is checked and frame 0
//! decoded before tracking starts, and the outputs are written only after the last frame, so
//! a bad PNG found later fails with an error naming it and leaves no output file behind.

pub mod board;
pub mod colours;
pub mod hue_table;
pub mod out_of_step;
pub mod output;

use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Result, anyhow, bail};
use evorec_core::colour::ColourModel;
use evorec_core::limits::DEFAULT_GRID;

use crate::sim::scenario::HOST_POPULATION_CAPACITY;
use evorec_core::ga::SearchSpace;
use evorec_core::kinematics::Chain;
use evorec_core::pose::Psi;
use evorec_core::tracker::{Tracker, TrackerConfig};
use evorec_core::tuning::Tuning;
use image::RgbImage;
use indicatif::ProgressBar;
use nalgebra::Isometry3;

use crate::experiments::experiment::{Population, SetupError, setup_tracker};
pub use crate::experiments::truth as eval;
use crate::recording::sequence::Sequence;
use crate::sim::board::search_space;
pub use board::FrameSource;
use board::{SensorPixels, SequenceBoard, TrackedFrame};
use evorec_core::image::Rgb565;
use hue_table::Rgb888Table;

/// What `evorec track` was asked to do.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackOptions {
    /// The tracker's tuning (the method, the GA's population and every other field of
    /// `evorec config`), checked against [`HOST_POPULATION_CAPACITY`] when the tracker is built.
    pub tuning: Tuning,
    /// Seed of the GA.
    pub seed: u64,
    /// Sample points per model row (default: the compiled one).
    pub points_per_row: Option<usize>,
    /// Track only the first N frames.
    pub frames: Option<usize>,
    /// `frames.csv` indices to draw overlays of.
    pub overlay: BTreeSet<u64>,
    /// Show a progress bar.
    pub progress: bool,
    /// The pixel format the tracker reads the PNGs in.
    pub pixels: Pixels,
    /// `estimate.tum` gives each frame's ROS stamp instead of the time since the origin
    /// (a bag, or a sequence with `stamp_origin_s`).
    pub absolute_stamps: bool,
    /// Stop with an error when the two cameras' images are out of step ([`out_of_step`]).
    pub check_pairing: bool,
}

/// The pixel format `evorec track` hands the decoded PNGs to the tracker in.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Pixels {
    /// The PNG's own 8-bit RGB (the hue of every sampled pixel exact): the host's default.
    #[default]
    Rgb888,
    /// Truncated to RGB565 first, as a board's camera sensor delivers pixels: what the
    /// firmware would see of the same scene.
    Rgb565,
}

impl Pixels {
    /// The name used on the command line and in `summary.json`.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Rgb888 => "rgb888",
            Self::Rgb565 => "rgb565",
        }
    }
}

impl Default for TrackOptions {
    fn default() -> Self {
        Self {
            tuning: Tuning::DEFAULT,
            seed: 1,
            points_per_row: None,
            frames: None,
            overlay: BTreeSet::new(),
            progress: false,
            pixels: Pixels::default(),
            absolute_stamps: false,
            check_pairing: true,
        }
    }
}

/// The result of tracking a sequence.
#[derive(Debug, Clone)]
pub struct TrackOutput {
    /// Published frames, in order.
    pub tracked: Vec<TrackedFrame>,
    /// Frames the tracker refused.
    pub rejected: u32,
    /// RGB images of the overlay frames: (position in frames.csv, left, right).
    pub kept: Vec<(usize, RgbImage, RgbImage)>,
    /// Wall-clock time of the tracking loop, decoding included (s).
    pub seconds: f64,
    /// The options used.
    pub options: TrackOptions,
    /// The colour model of the block's faces as the tracker learnt it by the last frame.
    pub colours: ColourModel,
    /// The shift of the silhouette rows the tracker learnt by the last frame (pixel widths
    /// outwards, `evorec_core::edge`).
    pub edge_shift_px: f32,
}

fn check_sizes(opts: &TrackOptions) -> Result<()> {
    opts.tuning.validate(HOST_POPULATION_CAPACITY)?;
    if let Some(g) = opts.points_per_row {
        crate::output::rows::check("--points-per-row", g)?;
    }
    Ok(())
}

/// The search space of a sequence: `[search]`, else the simulator's default box.
///
/// # Errors
/// An invalid `[search]` box.
pub fn search_of(seq: &Sequence) -> Result<SearchSpace> {
    match &seq.manifest.raw.search {
        Some(s) => SearchSpace::new_checked(s.min_m.map(|v| v as f32), s.max_m.map(|v| v as f32))
            .map_err(|e| anyhow!("{}: search: {e}", seq.dir.join("sequence.toml").display())),
        None => Ok(search_space()),
    }
}

/// Tracks `seq`: dispatches on the arm's number of joints.
///
/// # Errors
/// Unsupported options or arm, a bad first frame, a bad PNG found later (naming the file).
pub fn run(seq: &Sequence, opts: &TrackOptions) -> Result<TrackOutput> {
    let files = board::SequenceFiles { frames: Arc::new(seq.frames.clone()), cams: (seq.rig.left, seq.rig.right) };
    run_with(seq, Box::new(files), opts)
}

/// Tracks `seq` with its images from `source` (its frames in order).
///
/// # Errors
/// As [`run`].
pub fn run_with(seq: &Sequence, source: Box<dyn FrameSource>, opts: &TrackOptions) -> Result<TrackOutput> {
    check_sizes(opts)?;
    match seq.robot.dof() {
        6 => run_dof::<6>(seq, source, opts, seq.robot.chain::<6>()?),
        7 => run_dof::<7>(seq, source, opts, seq.robot.chain::<7>()?),
        n => bail!(
            "{}: the chain from {} to {} has {n} movable joints; evorec tracks arms of 6 or 7",
            seq.dir.join(&seq.manifest.raw.robot.urdf).display(),
            seq.manifest.raw.robot.base_link,
            seq.manifest.raw.robot.flange_link
        ),
    }
}

/// The tracker configuration of a sequence.
///
/// # Errors
/// Invalid search box.
pub fn config<const DOF: usize>(seq: &Sequence, arm: Chain<DOF>, opts: &TrackOptions) -> Result<TrackerConfig<DOF>> {
    Ok(TrackerConfig {
        rig: seq.rig,
        block: seq.block,
        arm,
        flange_to_camera: seq.manifest.flange_to_right.cast(),
        search: search_of(seq)?,
        seed: opts.seed,
        tuning: opts.tuning,
    })
}

/// The tracker over `seq` with `DOF` joints: dispatches on the pixel format and the row size.
fn run_dof<const DOF: usize>(
    seq: &Sequence,
    source: Box<dyn FrameSource>,
    opts: &TrackOptions,
    arm: Chain<DOF>,
) -> Result<TrackOutput> {
    let rows = opts.points_per_row.unwrap_or(DEFAULT_GRID);
    match opts.pixels {
        Pixels::Rgb888 => {
            crate::with_rows!("--points-per-row", rows, G => run_format::<DOF, Rgb888Table, G>(seq, source, opts, arm))
        }
        Pixels::Rgb565 => {
            crate::with_rows!("--points-per-row", rows, G => run_format::<DOF, Rgb565, G>(seq, source, opts, arm))
        }
    }
}

/// The tracker over `seq` with `DOF` joints and `G` points per sample row, reading frames in
/// pixel format `F`.
fn run_format<const DOF: usize, F: SensorPixels, const G: usize>(
    seq: &Sequence,
    source: Box<dyn FrameSource>,
    opts: &TrackOptions,
    arm: Chain<DOF>,
) -> Result<TrackOutput> {
    // Without an initial pose the tracker starts searching: uniform population, and the
    // colour-blob acquisition (evorec_core::acquire) seeds it until it tracks.
    let population = match &seq.manifest.initial_pose {
        Some(pose) => Population::Around(Psi::from_isometry(&pose.cast::<f32>())),
        None => Population::Redrawn,
    };
    let mut tracker: Tracker<DOF, HOST_POPULATION_CAPACITY, G> = setup_tracker(config(seq, arm, opts)?, population)
        .map_err(|e| match e {
            SetupError::InitialPose(e) => anyhow!("target.initial_pose: {e}"),
            e => anyhow!("{e}"),
        })?;
    let end = opts.frames.map_or(seq.frames.len(), |n| n.min(seq.frames.len()));
    if end == 0 {
        bail!("--frames 0: nothing to track");
    }
    let overlay: BTreeSet<usize> =
        seq.frames.iter().enumerate().filter(|(_, f)| opts.overlay.contains(&f.index)).map(|(i, _)| i).collect();
    let keep: Arc<dyn Fn(usize) -> bool + Send + Sync> = Arc::new(move |i| overlay.contains(&i));
    let (rx, reader) = board::spawn_reader::<F>(source, end, keep);
    // Frame 0 is received here, so a bad first image fails before anything runs.
    let first = match rx.recv() {
        Ok(Ok(first)) => first,
        Ok(Err(e)) => return Err(e.into()),
        Err(_) => bail!("the image reader stopped before the first frame"),
    };
    let progress = opts.progress.then(|| progress_bar(end as u64));
    let mut b = SequenceBoard::<F>::new(seq, first, rx, end, progress.clone(), opts.check_pairing);
    F::prepare();
    let n = F::BYTES_PER_PIXEL * usize::from(seq.rig.right.width()) * usize::from(seq.rig.right.height());
    let (mut left, mut right) = (vec![0u8; n], vec![0u8; n]);
    let t0 = Instant::now();
    let stats = evorec_core::board::run(&mut b, &mut tracker, &mut left, &mut right, u32::MAX);
    let seconds = t0.elapsed().as_secs_f64();
    let (tracked, kept) = b.into_outputs();
    reader.join().map_err(|_| anyhow!("the image reader thread panicked"))?;
    if let Some(p) = progress {
        p.finish_and_clear();
    }
    let stats = stats.map_err(|e| anyhow!("tracking stopped: {e}"))?;
    let (colours, edge_shift_px) = (*tracker.colours(), tracker.edge_shift_px());
    Ok(TrackOutput { tracked, rejected: stats.rejected, kept, seconds, options: opts.clone(), colours, edge_shift_px })
}

fn progress_bar(len: u64) -> ProgressBar {
    crate::output::logging::progress_bar_of(len, "frames")
}

/// The estimate of a tracked frame as a pose (f64).
pub fn estimate_pose(t: &TrackedFrame) -> Isometry3<f64> {
    eval::isometry_of(&t.estimate)
}
