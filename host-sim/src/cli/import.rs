//! `evorec import`: a ROS 2 bag written as a recorded sequence.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use evorec_sim::rig::bag;

use super::track::BagArgs;

#[derive(clap::Args, Debug)]
pub struct ImportArgs {
    /// The bag.
    bag: PathBuf,
    /// The rig file (`evorec-rig/1`): topics, frames and the block.
    #[arg(long)]
    rig: PathBuf,
    /// Sequence directory to create (must not exist or be empty).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    bag_args: BagArgs,
}

impl ImportArgs {
    pub fn run(self, progress: bool) -> Result<()> {
        let t0 = Instant::now();
        let rig = bag::Rig::load(&self.rig)?;
        let b = bag::load(&self.bag, &rig, &self.bag_args.options(), &self.out)?;
        b.report.log();
        let bar = progress.then(|| evorec_sim::output::logging::progress_bar_of(b.pairs.len() as u64, "pairs"));
        bag::import::import(&b, &self.out, bar.as_ref())?;
        if let Some(bar) = bar {
            bar.finish_and_clear();
        }
        let secs = t0.elapsed().as_secs_f64();
        if progress {
            self.print(&b, secs);
        }
        match &b.cut {
            Some(cut) => {
                anyhow::bail!("{cut}: imported the {} frames before it into {}", b.pairs.len(), self.out.display())
            }
            None => Ok(()),
        }
    }

    /// The lines a run prints on stdout (none with -q).
    fn print(&self, b: &bag::BagSequence, secs: f64) {
        println!("{}", b.report.describe());
        println!(
            "imported {} frame pairs in {secs:.1} s ({:.0} pairs/s); wrote {}",
            b.pairs.len(),
            b.pairs.len() as f64 / secs.max(1e-9),
            self.out.display()
        );
    }
}
