//! `evorec rig`: a draft rig file from a bag's topics, frames and URDF.

use std::path::PathBuf;

use anyhow::Result;
use evorec_sim::rig::bag;

#[derive(clap::Args, Debug)]
pub struct RigArgs {
    /// The bag (directory or .mcap file).
    bag: PathBuf,
    /// The rig file to write (must not exist).
    #[arg(long)]
    out: PathBuf,
}

impl RigArgs {
    pub fn run(self) -> Result<()> {
        if self.out.exists() {
            anyhow::bail!("{}: exists; evorec rig does not overwrite a rig file", self.out.display());
        }
        let draft = bag::rigfile::draft(&self.bag)?;
        evorec_sim::output::io::write_bytes(&self.out, draft.text.as_bytes())?;
        for key in &draft.open {
            log::warn!("{}: left to you: {key}", self.out.display());
        }
        log::warn!("{}: add the block's [target] section (written commented out)", self.out.display());
        Ok(())
    }
}
