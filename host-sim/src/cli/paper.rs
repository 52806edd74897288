//! `evorec paper`: the paper's grid, the grid over the block's own motion, or both.

use std::ops::RangeInclusive;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::ValueEnum;
use evorec_core::tuning::Feedforward;
use evorec_sim::experiments::{paper, paper_seeds, target_grid};
use evorec_sim::sim::motion::MotionKind;
use evorec_sim::sim::scenario::{Scenario, load_light};

use super::{OutArgs, load};

#[derive(clap::Args, Debug)]
pub struct PaperArgs {
    #[command(flatten)]
    out: OutArgs,
    /// Scenario whose camera, target and seed the grid uses (default: built-in defaults,
    /// seed 1, 72 s); the target grid also takes its duration (the paper's is 72 s).
    #[arg(long)]
    base: Option<PathBuf>,
    /// A TOML file holding a `[render]` table (a scenario's keys, e.g.
    /// scenarios/light/camera_like.toml): the light of every run, in place of the base's.
    #[arg(long, value_name = "FILE")]
    light: Option<PathBuf>,
    /// Which grid: the paper's, the one over the block's own motion, or both.
    #[arg(long, value_enum, default_value_t = Grid::Paper)]
    grid: Grid,
    /// Run only this method's cells (ga, ff or ff+target; the target grid has ff and
    /// ff+target).
    #[arg(long, value_parser = str::parse::<Feedforward>)]
    method: Option<Feedforward>,
    /// Seed sweep instead of one grid: the sweep's cells (motion A at every ω, motion B at
    /// ω > 0, of `--method`, default ff) run once per GA seed FIRST..LAST (both included), the
    /// base's seed replaced; writes DIR/cells_FIRST_LAST.csv (columns motion, omega, seed, F,
    /// x_mm, y_mm, z_mm, e1, e2, e3: one row per seed and cell) and the runs in DIR/runs/.
    #[arg(long, value_name = "FIRST..LAST", value_parser = paper_seeds::parse_seeds, conflicts_with = "grid")]
    seeds: Option<RangeInclusive<u64>>,
    /// With --seeds: only these cells, MOTION:OMEGA, comma-separated (e.g. A:0,A:0.25,B:1).
    #[arg(long, value_delimiter = ',', requires = "seeds", value_parser = paper_seeds::parse_cell)]
    cells: Vec<(MotionKind, f64)>,
}

/// The grids of `evorec paper`.
#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
enum Grid {
    /// The paper's grid (motions A/B × ω × GA, FF, FF + target).
    Paper,
    /// The block's own motion (conveyor speeds, ω_o) under motion A at 0.5 rad/s.
    Target,
    /// Both.
    Both,
}

impl PaperArgs {
    pub fn run(self, progress: bool) -> Result<()> {
        let base = self.base()?;
        let out = self.out.create()?;
        let t0 = Instant::now();
        if let Some(seeds) = self.seeds.clone() {
            let (runs, path) = paper_seeds::run(&self.sweep_cells(), seeds, &base, out, progress)?;
            println!("{} runs in {:.1} s; wrote {}", runs.len(), t0.elapsed().as_secs_f64(), path.display());
            return Ok(());
        }
        let wanted = |m: Feedforward| self.method.is_none_or(|w| w == m);
        let mut runs = 0;
        if self.grid != Grid::Target {
            let cells: Vec<_> = paper::grid().into_iter().filter(|c| wanted(c.method)).collect();
            let results = paper::run_grid_of(&cells, &base, out, progress)?;
            println!("{}", paper::markdown(&results));
            runs += results.len();
        }
        if self.grid != Grid::Paper {
            let cells: Vec<_> = target_grid::grid().into_iter().filter(|c| wanted(c.method)).collect();
            let results = target_grid::run_grid(&cells, &base, out, progress)?;
            println!("{}", target_grid::markdown(&results));
            runs += results.len();
        }
        println!("{runs} runs in {:.1} s; wrote {}", t0.elapsed().as_secs_f64(), out.display());
        Ok(())
    }

    /// The cells of `--seeds`: `--cells` in their order, else all of the sweep's.
    fn sweep_cells(&self) -> Vec<paper::Cell> {
        let all = paper_seeds::cells(self.method.unwrap_or(Feedforward::On));
        if self.cells.is_empty() {
            return all;
        }
        self.cells.iter().filter_map(|(m, w)| all.iter().find(|c| c.motion == *m && c.omega == *w).copied()).collect()
    }

    /// `--base`, or the built-in defaults with the paper's 1-step GA (one generation per
    /// frame; a `--base` file sets its own `generations_per_frame`), under `--light`'s light.
    fn base(&self) -> Result<Scenario> {
        let mut s = match &self.base {
            Some(p) => load(p)?,
            None => {
                let mut s = Scenario::new(1, paper::DURATION_S, Feedforward::On);
                s.tracker.0.generations_per_frame = 1;
                s
            }
        };
        if let Some(path) = &self.light {
            s.render = load_light(path, s.frame_period_s)?;
        }
        Ok(s)
    }
}
