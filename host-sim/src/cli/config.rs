//! `evorec config`: the effective tracker configuration.

use std::path::PathBuf;

use anyhow::Result;
use evorec_core::tuning::Tuning;
use evorec_sim::sim::scenario::TrackerTable;

use super::{ConfigArg, load};

#[derive(clap::Args, Debug)]
pub struct ConfigArgs {
    /// A scenario whose `[tracker]` table to print (default: the core's defaults).
    scenario: Option<PathBuf>,
    #[command(flatten)]
    config: ConfigArg,
}

impl ConfigArgs {
    pub fn run(self) -> Result<()> {
        let base = match &self.scenario {
            Some(path) => *load(path)?.tuning(),
            None => Tuning::DEFAULT,
        };
        print!("{}", TrackerTable(self.config.over(base)?).to_toml());
        Ok(())
    }
}
