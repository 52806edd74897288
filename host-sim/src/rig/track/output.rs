//! What `evorec track` writes: `trace.csv` (the columns of `evorec run`'s trace), the estimates
//! as `estimate.tum`, `summary.json`, the plots and `overlay_<N>.png`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use evorec_core::camera::Pinhole;
use evorec_core::limits::DEFAULT_GRID;
use evorec_core::model::{Block, SurfaceStrips};
use evorec_core::status::Status;
use evorec_core::tracker::Feedforward;
use image::RgbImage;
use nalgebra::{Isometry3, Point3};
use serde::Serialize;

use super::TrackOutput;
use super::eval::{self, FrameError, Rms, WrongTracking};
use crate::recording::sequence::Sequence;
use crate::sim::render;

/// `summary.json` of a tracked sequence.
#[derive(Debug, Clone, Serialize)]
pub struct TrackSummary {
    /// The sequence's name.
    pub sequence: String,
    /// Feedforward on (of the arm, and with `method = "ff+target"` of the target too).
    pub feedforward: bool,
    /// `ga`, `ff` or `ff+target` (`evorec track --method`).
    pub method: &'static str,
    /// GA population used.
    pub population: usize,
    /// Pixel format the tracker read the PNGs in (`rgb888` or `rgb565`, `evorec track --pixels`).
    pub pixels: &'static str,
    /// GA seed.
    pub seed: u64,
    /// Frames tracked.
    pub frames: usize,
    /// Frames the tracker refused.
    pub rejected: u32,
    /// Mean fitness `F̄`.
    #[serde(rename = "F_mean")]
    pub f_mean: f64,
    /// Errors over all frames against `groundtruth.tum` (null without it).
    pub all: Option<Rms>,
    /// `frames.csv` index of the first frame from which the estimate stays within 10 mm and
    /// 5° to the end (null if never, or without ground truth).
    pub within_from_frame: Option<u64>,
    /// Its capture time (s).
    pub within_from_t_s: Option<f64>,
    /// `frames.csv` index of the first frame reported as tracking (null if none).
    pub first_tracking_frame: Option<u64>,
    /// Fraction of the frames reported as tracking.
    pub tracking_fraction: f64,
    /// Frames in which the best pose fits one camera and not the other: its better camera
    /// scores at least [`SEEN_FITNESS`] and its worse camera below
    /// [`MISMATCH_FITNESS`] of the expected
    /// fitness (the colour model's, at the end of the run). Left and right images out of step
    /// give many; a pair in step, none once the block is found.
    pub camera_mismatch_frames: usize,
    /// `camera_mismatch_frames / frames`.
    pub camera_mismatch_fraction: f64,
    /// Errors over the frames from `within_from_frame` on.
    pub after_within: Option<Rms>,
    /// How often `tracking` was wrong, over the frames with ground truth (flattened into the
    /// top level; absent without ground truth).
    #[serde(flatten)]
    pub wrong_tracking: Option<WrongTracking>,
    /// The half turns errors are taken modulo (the block's colour symmetry).
    pub symmetries: Vec<&'static str>,
    /// Frames per second of the tracking loop, PNG decoding included.
    pub frames_per_s: f64,
    /// The shift of the silhouette rows learnt by the last frame, pixel widths outwards
    /// (`evorec_core::edge`; 0 until the block is tracked, negative for a camera that needs
    /// more than a quarter of a pixel covered to read it as the face).
    pub edge_shift_px: f32,
    /// Version of evorec.
    pub evorec_version: &'static str,
    /// What was found in the ROS 2 bag tracked (absent for a sequence directory): the bag
    /// reader's report, as JSON, so that tracking does not depend on the bag reader.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bag: Option<serde_json::Value>,
    /// `true` when the input ended early (a truncated bag): the results cover the frames
    /// before that point only (absent otherwise).
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub partial: bool,
}

/// The better camera's fitness from which the block counts as seen ([`TrackSummary::camera_mismatch_frames`]).
pub const SEEN_FITNESS: f32 = 0.5;

/// The share of [`TrackSummary::camera_mismatch_frames`] from which `evorec track` warns that
/// the left and right images look out of step.
pub const OUT_OF_STEP_WARN_FRACTION: f64 = 0.2;

impl TrackSummary {
    /// The warning of a run whose left and right images look out of step (at least
    /// [`OUT_OF_STEP_WARN_FRACTION`] of the frames fit one camera and not the other).
    pub fn out_of_step_warning(&self) -> Option<String> {
        (self.camera_mismatch_fraction >= OUT_OF_STEP_WARN_FRACTION).then(|| {
            format!(
                "left and right images look out of step: in {} of {} frames ({:.0} %) the best pose fits one camera \
                 and not the other (a constant offset or a dropped frame between the left and right images, or the \
                 block hidden from one camera); the status does not check this, so estimates reported as tracking \
                 on such frames may be wrong",
                self.camera_mismatch_frames,
                self.frames,
                100.0 * self.camera_mismatch_fraction
            )
        })
    }
}

/// A camera scoring below this share of the expected fitness while the other fits
/// ([`SEEN_FITNESS`]) does not see the pose the other sees.
pub const MISMATCH_FITNESS: f32 = 0.75;

/// Frames of `out` whose best pose fits one camera and not the other
/// ([`TrackSummary::camera_mismatch_frames`]).
fn camera_mismatch_frames(out: &TrackOutput) -> usize {
    let floor = MISMATCH_FITNESS * out.colours.expected_fitness();
    let mismatch = |[l, r]: [f32; 2]| l.max(r) >= SEEN_FITNESS && (l.min(r) < floor || l.min(r).is_nan());
    out.tracked.iter().filter(|t| mismatch(t.camera_fitness)).count()
}

/// One `trace.csv` row's truth (aligned modulo symmetry) and the errors, per frame.
pub struct Evaluation {
    /// Aligned truth ψ per tracked frame (`None` without ground truth).
    pub truth: Vec<Option<[f64; 6]>>,
    /// Errors per tracked frame (empty without ground truth).
    pub errors: Vec<FrameError>,
    /// The summary.
    pub summary: TrackSummary,
}

/// Evaluates a run against the sequence's ground truth.
pub fn evaluate(seq: &Sequence, out: &TrackOutput) -> Evaluation {
    let syms = eval::colour_symmetries(&seq.block.face_hues_deg);
    let mut truth = Vec::with_capacity(out.tracked.len());
    let mut errors = Vec::new();
    let mut checked = Vec::new();
    for t in &out.tracked {
        match seq.groundtruth.as_ref().and_then(|g| g.get(t.i)) {
            Some(gt) => {
                let (e, aligned) = eval::frame_error(&t.estimate, gt, &syms);
                errors.push(e);
                checked.push((t.status, e.within()));
                truth.push(Some(aligned));
            }
            None => truth.push(None),
        }
    }
    let n = out.tracked.len().max(1) as f64;
    let settled = eval::settled_from(&errors);
    let mismatch = camera_mismatch_frames(out);
    let settled_frame = settled.map(|k| &seq.frames[out.tracked[k].i]);
    let summary = TrackSummary {
        sequence: seq.name(),
        feedforward: out.options.tuning.feedforward != Feedforward::Off,
        method: out.options.tuning.feedforward.name(),
        population: out.options.tuning.ga.population,
        pixels: out.options.pixels.as_str(),
        seed: out.options.seed,
        frames: out.tracked.len(),
        rejected: out.rejected,
        f_mean: out.tracked.iter().map(|t| f64::from(t.fitness)).sum::<f64>() / n,
        all: Rms::of(&errors),
        within_from_frame: settled_frame.map(|f| f.index),
        within_from_t_s: settled_frame.map(|f| f.t_s),
        first_tracking_frame: out.tracked.iter().find(|t| t.status == Status::Tracking).map(|t| seq.frames[t.i].index),
        tracking_fraction: out.tracked.iter().filter(|t| t.status == Status::Tracking).count() as f64 / n,
        camera_mismatch_frames: mismatch,
        camera_mismatch_fraction: mismatch as f64 / n,
        after_within: settled.and_then(|k| Rms::of(&errors[k..])),
        wrong_tracking: (!checked.is_empty()).then(|| WrongTracking::of(checked)),
        symmetries: syms.iter().map(|(n, _)| *n).collect(),
        frames_per_s: out.tracked.len() as f64 / out.seconds.max(1e-9),
        edge_shift_px: out.edge_shift_px,
        evorec_version: env!("CARGO_PKG_VERSION"),
        bag: None,
        partial: false,
    };
    Evaluation { truth, errors, summary }
}

fn write_trace(path: &Path, seq: &Sequence, out: &TrackOutput, ev: &Evaluation) -> Result<()> {
    crate::output::io::write_atomic(path, |file| write_trace_to(file, seq, out, ev))
}

fn write_trace_to(file: &mut dyn std::io::Write, seq: &Sequence, out: &TrackOutput, ev: &Evaluation) -> Result<()> {
    let mut w = csv::Writer::from_writer(file);
    w.write_record(crate::output::io::trace_columns(seq.joints.dof()))?;
    let psi_cells = |p: &[f64; 6]| -> Vec<String> {
        let mut v: Vec<String> = p[..3].iter().map(|x| format!("{:.4}", x * 1e3)).collect();
        v.extend(p[3..].iter().map(|x| format!("{x:.6}")));
        v
    };
    for (t, truth) in out.tracked.iter().zip(&ev.truth) {
        let mut rec: Vec<String> = vec![format!("{:.6}", seq.frames[t.i].t_s)];
        rec.extend(t.q.iter().chain(t.qd.iter()).map(|v| format!("{v:.6}")));
        match truth {
            Some(p) => rec.extend(psi_cells(p)),
            None => rec.extend(std::iter::repeat_n(String::new(), 6)),
        }
        rec.extend(psi_cells(&t.estimate.0.map(f64::from)));
        rec.push(format!("{:.5}", t.fitness));
        rec.push(t.status.as_str().to_owned());
        rec.push(String::new());
        w.write_record(&rec)?;
    }
    w.flush()?;
    Ok(())
}

/// The model's sample points at `cam_from_model` drawn over `img` (faces turned to the camera:
/// inner rows white, contour rows black), as `evorec render` draws them.
pub fn draw_model(img: &mut RgbImage, cam: &Pinhole, cam_from_model: &Isometry3<f32>, block: &Block) -> Result<()> {
    let model = SurfaceStrips::<DEFAULT_GRID>::new(block).map_err(|e| anyhow::anyhow!("model: {e}"))?;
    let project = |p: Point3<f32>| cam.project(&(cam_from_model * p)).ok().map(|uv| (uv.x, uv.y));
    for k in 0..6 {
        let n_cam = cam_from_model.rotation * Block::normal(k);
        let c = cam_from_model * Point3::from(Block::normal(k) * model.half_size()[k % 3]);
        if n_cam.dot(&c.coords) >= 0.0 {
            continue;
        }
        let inner: Vec<_> = model.inner_points(k).filter_map(project).collect();
        let outer: Vec<_> = model.outer_points(k).filter_map(project).collect();
        render::draw_points(img, &inner, [255, 255, 255]);
        render::draw_points(img, &outer, [0, 0, 0]);
    }
    Ok(())
}

/// Left and right images side by side with the model drawn at `estimate` (`^CR T_M`).
///
/// # Errors
/// An invalid block.
pub fn overlay(seq: &Sequence, left: &RgbImage, right: &RgbImage, estimate: &Isometry3<f32>) -> Result<RgbImage> {
    let (mut l, mut r) = (left.clone(), right.clone());
    draw_model(&mut l, &seq.rig.left, &(seq.rig.left_from_right * estimate), &seq.block)?;
    draw_model(&mut r, &seq.rig.right, estimate, &seq.block)?;
    let mut out = RgbImage::new(l.width() + r.width(), l.height().max(r.height()));
    image::imageops::replace(&mut out, &l, 0, 0);
    image::imageops::replace(&mut out, &r, i64::from(l.width()), 0);
    Ok(out)
}

/// Writes every output of a tracked sequence into `dir`; returns the files written.
///
/// # Errors
/// I/O errors.
pub fn write_all(seq: &Sequence, out: &TrackOutput, ev: &Evaluation, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let mut written = Vec::new();
    let trace = dir.join("trace.csv");
    write_trace(&trace, seq, out, ev)?;
    written.push(trace.clone());
    let poses: Vec<(f64, Isometry3<f64>)> =
        out.tracked.iter().map(|t| (seq.frames[t.i].t_s, super::estimate_pose(t))).collect();
    let times = match (seq.manifest.raw.stamp_origin_s, out.options.absolute_stamps) {
        (Some(origin), false) => crate::output::io::TumTimes::SinceStamp(origin),
        (Some(origin), true) => crate::output::io::TumTimes::Absolute(origin),
        (None, _) => crate::output::io::TumTimes::Sequence,
    };
    written.push(crate::output::io::write_estimate_tum(dir, &poses, times)?);
    for (i, l, r) in &out.kept {
        if let Some(t) = out.tracked.iter().find(|t| t.i == *i) {
            let img = overlay(seq, l, r, &super::estimate_pose(t).cast())?;
            let path = dir.join(format!("overlay_{}.png", seq.frames[*i].index));
            crate::output::io::write_png(&path, &img)?;
            written.push(path);
        }
    }
    let title = format!("{} ({})", seq.name(), ev.summary.method);
    written.extend(crate::output::plot::plot_trace(&trace, dir, &title)?);
    let summary = dir.join("summary.json");
    crate::output::io::write_json(&summary, &ev.summary)?;
    written.push(summary);
    crate::output::io::write_tracker_config(dir, &out.options.tuning)?;
    written.push(dir.join("config.toml"));
    Ok(written)
}
