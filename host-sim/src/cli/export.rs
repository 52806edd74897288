//! `evorec export`: a scenario written as a recorded sequence.

use std::path::PathBuf;

use anyhow::Result;
use evorec_sim::rig::export;

use super::load;

#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// Scenario file (TOML).
    scenario: PathBuf,
    /// Sequence directory to create (must not exist or be empty).
    #[arg(long)]
    out: PathBuf,
}

impl ExportArgs {
    pub fn run(self, progress: bool) -> Result<()> {
        let s = load(&self.scenario)?;
        let name = self.scenario.file_stem().map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        let bar = progress
            .then(|| evorec_sim::output::logging::progress_bar(u64::from(evorec_sim::sim::board::frame_total(&s))));
        let stats = export::export(&s, &name, &self.out, bar.clone())?;
        if let Some(b) = bar {
            b.finish_and_clear();
        }
        println!("wrote {} ({} frames, {} joint samples)", self.out.display(), stats.frames, stats.joint_samples);
        Ok(())
    }
}
