//! `evorec track BAG`: the tracker on a bag's frames as they stream, and its outputs — those of
//! a sequence (with the bag's report in `summary.json`) plus the results bag
//! (`estimate.mcap` and `metadata.yaml`, [`super::write_mcap`]).

use std::path::Path;

use anyhow::Result;

use super::BagSequence;
use super::results::frame_results;
use super::source::BagFrames;
use super::write_mcap::{self, BagInput, results_bag};
use crate::rig::track::{self, TrackOptions, output};

/// The results bag's `metadata.yaml`, next to [`write_mcap::FILE`] in the output directory.
pub const METADATA: &str = "metadata.yaml";

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
    let frames = frame_results(bag, &result)?;
    let input = BagInput {
        frames: &frames,
        output: &bag.rig.output,
        camera_frame: &bag.rig.frames.right_camera,
        base_frame: &bag.rig.frames.base_link,
        block: &bag.seq.block,
    };
    let results = results_bag(&input)?;
    let metadata = results.metadata.to_yaml()?;
    output::write_all(&bag.seq, &result, &ev, out)?;
    crate::output::io::write_bytes(&out.join(write_mcap::FILE), &results.mcap)?;
    crate::output::io::write_bytes(&out.join(METADATA), metadata.as_bytes())?;
    Ok(ev)
}
