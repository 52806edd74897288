//! `evorec render`: one frame pair of a scenario.

use std::path::PathBuf;

use anyhow::{Context, Result};
use evorec_sim::output::frame;

use super::{OutArgs, load};

#[derive(clap::Args, Debug)]
pub struct RenderArgs {
    /// Scenario file (TOML).
    scenario: PathBuf,
    /// Frame index (frame n is captured at n · frame_period_s).
    #[arg(long, default_value_t = 0)]
    frame: u32,
    #[command(flatten)]
    out: OutArgs,
}

impl RenderArgs {
    pub fn run(self) -> Result<()> {
        let s = load(&self.scenario)?;
        let files = frame::render_frame(&s, self.frame, self.out.create()?).context("rendering")?;
        for f in files {
            println!("wrote {}", f.display());
        }
        Ok(())
    }
}
