//! `evorec colours`: the block's face colours as the rig's cameras see them.

use std::path::PathBuf;

use anyhow::{Context, Result};
use evorec_sim::recording::sequence::Sequence;
use evorec_sim::rig::track::colours::ColourReport;
use evorec_sim::rig::{bag, track};

use super::ConfigArg;
use super::track::TrackArgs;

#[derive(clap::Args, Debug)]
pub struct ColoursArgs {
    /// Sequence directory, or a ROS 2 bag (with `--rig`).
    seq: PathBuf,
    /// The rig file of a bag.
    #[arg(long)]
    rig: Option<PathBuf>,
    /// A frame in which the block is in view of both cameras: the tracker runs from the
    /// first frame to `--frames` frames past this one.
    #[arg(long, default_value_t = 0)]
    frame: usize,
    /// Frames tracked past `--frame` (60: 2 s at 30 frames/s).
    #[arg(long, default_value_t = 60)]
    frames: usize,
    /// Seed of the GA.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    config: ConfigArg,
    /// Where to write the `[target]` table with the measured hues.
    #[arg(long, default_value = "colours.toml")]
    out: PathBuf,
}

impl ColoursArgs {
    pub fn run(self, progress: bool) -> Result<()> {
        let mut opts = TrackArgs::default_options(&self.config, self.seed, progress)?;
        opts.frames = Some(self.frame.saturating_add(self.frames).saturating_add(1));
        let (block, output) = match &self.rig {
            Some(rig) => {
                let rig = bag::Rig::load(rig)?;
                let b = bag::load(&self.seq, &rig, &bag::BagOptions::default(), &self.seq)?;
                let out = track::run_with(&b.seq, Box::new(bag::source::BagFrames::new(&b)), &opts)?;
                (b.seq.block, out)
            }
            None => {
                let seq = Sequence::load(&self.seq)?;
                (seq.block, track::run(&seq, &opts)?)
            }
        };
        let report = ColourReport::of(&block, &output)?;
        println!("{}", report.describe());
        let source = format!("{} (frames 0 to {})", self.seq.display(), output.tracked.len().saturating_sub(1));
        std::fs::write(&self.out, report.to_toml(&source))
            .with_context(|| format!("writing {}", self.out.display()))?;
        println!("wrote {}", self.out.display());
        Ok(())
    }
}
