//! `evorec track BAG`: the tracker on a bag's frames as they stream, and its outputs — those of
//! a sequence (with the bag's report in `summary.json`) plus `estimate.mcap`.

use std::path::Path;

use anyhow::Result;

use super::BagSequence;
use super::source::BagFrames;
use super::write_mcap::{FrameResult, estimate_mcap};
use crate::track::{self, TrackOptions, output};

/// Tracks `bag` and writes every output into `out` (only once every frame was tracked; for a
/// bag cut short, [`BagSequence::cut`], those before the cut, with `summary.json` saying
/// `"partial": true`).
///
/// # Errors
/// As [`track::run_with`], and I/O errors.
pub fn track_and_write(bag: &BagSequence, opts: &TrackOptions, out: &Path) -> Result<output::Evaluation> {
    let result = track::run_with(&bag.seq, Box::new(BagFrames::new(bag)), opts)?;
    let mut ev = output::evaluate(&bag.seq, &result);
    ev.summary.bag = Some(serde_json::to_value(&bag.report)?);
    ev.summary.partial = bag.cut.is_some();
    let frames: Vec<FrameResult> = result
        .tracked
        .iter()
        .map(|t| FrameResult {
            stamp_ns: bag.stamps_ns.get(t.i).copied().unwrap_or(0),
            pose: track::estimate_pose(t),
            status: t.status.as_str(),
            fitness: t.fitness,
        })
        .collect();
    let mcap = estimate_mcap(&frames, &bag.rig.frames.right_camera)?;
    output::write_all(&bag.seq, &result, &ev, out)?;
    crate::io::write_bytes(&out.join("estimate.mcap"), &mcap)?;
    Ok(ev)
}
