//! `evorec timing`: M4 instructions, stack and memory of a GA generation.

use anyhow::Result;

use super::OutArgs;

#[derive(clap::Args, Debug)]
pub struct TimingArgs {
    #[command(flatten)]
    out: OutArgs,
    /// Board profile: `m4` (Cortex-M4F, STM32F4 at 168 MHz, 160×120) or `m7` (Cortex-M7,
    /// STM32H743 at 480 MHz, 320×240).
    #[arg(long, default_value = "m4", value_parser = ["m4", "m7"])]
    profile: String,
}

impl TimingArgs {
    pub fn run(self) -> Result<()> {
        let board = evorec_sim::firmware::timing::Board::by_name(&self.profile)
            .ok_or_else(|| anyhow::anyhow!("--profile {}: expected m4 or m7", self.profile))?;
        evorec_sim::firmware::timing::run(self.out.create()?, board)
    }
}
