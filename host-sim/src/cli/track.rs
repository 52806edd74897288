//! `evorec track`: a recorded sequence or a ROS 2 bag, and how a bag is read (shared with
//! `evorec import`).

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::Result;
use clap::ValueEnum;
use evorec_core::tuning::{Feedforward, Tuning};
use evorec_sim::recording::sequence::Sequence;
use evorec_sim::rig::{bag, track};
use evorec_sim::sim::scenario::HOST_POPULATION_CAPACITY;

use super::{ConfigArg, OutArgs};

#[derive(clap::Args, Debug)]
pub struct TrackArgs {
    /// Sequence directory (holds sequence.toml), or a ROS 2 bag (directory or .mcap file).
    seq: PathBuf,
    /// The rig file (`evorec-rig/1`) of a bag: its topics, frames and block.
    #[arg(long)]
    rig: Option<PathBuf>,
    #[command(flatten)]
    bag: BagArgs,
    #[command(flatten)]
    out: OutArgs,
    /// Plain 1-step GA (no motion feedforward; the same as `--method ga`).
    #[arg(long, conflicts_with = "method")]
    no_ff: bool,
    /// `ga` (plain 1-step GA), `ff` (+ the arm's motion fed forward) or `ff+target` (+ the
    /// target's own motion, estimated from past estimates, fed forward too; the default, as
    /// everywhere: a recorded target may move).
    #[arg(long, value_parser = method_values())]
    method: Option<Feedforward>,
    /// Seed of the GA.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// GA population size (16 up to the compiled capacity, 64: room for the acquisition's seeded and idle individuals).
    #[arg(long)]
    population: Option<usize>,
    /// Sample points per row of the surface-strips model (5, 6, 7 or 8; default the core's
    /// `DEFAULT_GRID`).
    #[arg(long)]
    points_per_row: Option<usize>,
    /// Track only the first N frames.
    #[arg(long)]
    frames: Option<usize>,
    /// Pixels the tracker reads: `rgb888` (the PNG's own colour) or `rgb565` (truncated
    /// first, as a board's camera sensor delivers them: what the firmware would see).
    #[arg(long, value_enum, default_value_t = TrackPixels::Rgb888)]
    pixels: TrackPixels,
    /// Frame indices (frames.csv `index`) to draw the model at its estimate over, e.g. 0,90.
    #[arg(long, value_delimiter = ',')]
    overlay: Vec<u64>,
    /// Write each frame's ROS `header.stamp` (s since the epoch, to the ns) as the time of
    /// estimate.tum, instead of the seconds since the whole second before the bag's first
    /// frame (a bag, or a sequence imported from one).
    #[arg(long)]
    absolute_stamps: bool,
    /// Track even when the two cameras' images look out of step (by default the run stops
    /// with an error naming the offset: each left image would be paired with a right one
    /// taken at another time).
    #[arg(long)]
    no_pairing_check: bool,
    /// Over the defaults; `--method`, `--no-ff` and `--population` replace its keys.
    #[command(flatten)]
    config: ConfigArg,
}

/// `evorec track --pixels`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
enum TrackPixels {
    /// The PNG's own 8-bit RGB.
    Rgb888,
    /// Truncated to RGB565 first (the board's sensor format).
    Rgb565,
}

impl From<TrackPixels> for track::Pixels {
    fn from(p: TrackPixels) -> Self {
        match p {
            TrackPixels::Rgb888 => Self::Rgb888,
            TrackPixels::Rgb565 => Self::Rgb565,
        }
    }
}

impl TrackArgs {
    pub fn run(self, progress: bool) -> Result<()> {
        let opts = self.options(progress)?;
        let out = &self.out.out;
        let bag_opts = self.bag.options();
        match &self.rig {
            Some(rig) => track_bag(&self.seq, rig, out, &opts, &bag_opts),
            None if bag::scan::is_bag(&self.seq) => {
                anyhow::bail!("{}: is a ROS 2 bag: give its rig file with --rig RIG.toml", self.seq.display())
            }
            None if self.bag.given() => {
                anyhow::bail!("--pair-tolerance-ms, --start and --end apply to a ROS 2 bag (with --rig)")
            }
            None => track_sequence(&self.seq, out, &opts),
        }
    }

    fn options(&self, progress: bool) -> Result<track::TrackOptions> {
        Ok(track::TrackOptions {
            tuning: self.tuning()?,
            seed: self.seed,
            points_per_row: self.points_per_row,
            frames: self.frames,
            overlay: self.overlay.iter().copied().collect(),
            progress,
            pixels: self.pixels.into(),
            absolute_stamps: self.absolute_stamps,
            check_pairing: !self.no_pairing_check,
        })
    }

    /// The options of a run with every default but the tuning's `config` file and the seed
    /// (`evorec colours`).
    pub fn default_options(config: &ConfigArg, seed: u64, progress: bool) -> Result<track::TrackOptions> {
        Ok(track::TrackOptions {
            tuning: config.over(Tuning::DEFAULT)?,
            seed,
            progress,
            ..track::TrackOptions::default()
        })
    }

    /// The tuning: the defaults, then the `--config` file, then `--method` (or `--no-ff`) and
    /// `--population`.
    fn tuning(&self) -> Result<Tuning> {
        let mut t = self.config.over(Tuning::DEFAULT)?;
        if let Some(m) = if self.no_ff { Some(Feedforward::Off) } else { self.method } {
            t.feedforward = m;
        }
        if let Some(p) = self.population {
            t.ga.population = p;
            if let Err(e) = t.validate(HOST_POPULATION_CAPACITY) {
                anyhow::bail!("--population {p}: {e}");
            }
        }
        Ok(t)
    }
}

fn track_sequence(dir: &Path, out: &Path, opts: &track::TrackOptions) -> Result<()> {
    let seq = Sequence::load(dir)?;
    if opts.absolute_stamps && seq.manifest.raw.stamp_origin_s.is_none() {
        anyhow::bail!(
            "--absolute-stamps: {} has no stamp_origin_s (only a bag, or a sequence imported from one, has stamps)",
            dir.join("sequence.toml").display()
        );
    }
    let t0 = Instant::now();
    let output = track::run(&seq, opts)?;
    let ev = track::output::evaluate(&seq, &output);
    track::output::write_all(&seq, &output, &ev, out)?;
    if let Some(w) = ev.summary.out_of_step_warning() {
        log::warn!("{}: {w}", dir.display());
    }
    if opts.progress {
        print_track(&ev.summary, t0, out);
    }
    Ok(())
}

/// `evorec track BAG --rig RIG`: the bag read (first pass), tracked while its images stream
/// (second pass); the outputs of a sequence plus the results bag (`estimate.mcap`,
/// `metadata.yaml`).
fn track_bag(
    path: &Path,
    rig: &Path,
    out: &Path,
    opts: &track::TrackOptions,
    bag_opts: &bag::BagOptions,
) -> Result<()> {
    let t0 = Instant::now();
    let rig = bag::Rig::load(rig)?;
    let b = bag::load(path, &rig, bag_opts, path)?;
    b.report.log();
    let ev = bag::track::track_and_write(&b, opts, out)?;
    if let Some(w) = ev.summary.out_of_step_warning() {
        log::warn!("{}: {w}", path.display());
    }
    // `opts.progress` is off with -q: nothing but errors then.
    if opts.progress {
        println!("{}", b.report.describe());
        print_track(&ev.summary, t0, out);
    }
    match &b.cut {
        Some(cut) => anyhow::bail!(
            "{cut}: tracked the {} frames before it; wrote {} (summary.json: \"partial\": true)",
            ev.summary.frames,
            out.display()
        ),
        None => Ok(()),
    }
}

fn print_track(s: &track::output::TrackSummary, t0: Instant, out: &Path) {
    print!(
        "{} frames in {:.1} s ({:.0} frames/s): F_mean {:.4}",
        s.frames,
        t0.elapsed().as_secs_f64(),
        s.frames_per_s,
        s.f_mean
    );
    print!(", tracking {:.0} % of the frames", 100.0 * s.tracking_fraction);
    if let Some(a) = &s.all {
        print!(", RMS x/y/z {:.2}/{:.2}/{:.2} mm", a.rms_x_mm, a.rms_y_mm, a.rms_z_mm);
        if let Some(r) = &a.rotation {
            print!(", RMS rotation {:.2} deg (max {:.2})", r.rms_rot_deg, r.max_rot_deg);
        }
        match s.within_from_frame {
            Some(f) => print!(", within 10 mm/5 deg from frame {f}"),
            None => print!(", never stays within 10 mm/5 deg"),
        }
    }
    println!("\nwrote {}", out.display());
}

/// How to read a bag (`track BAG --rig`, `import`).
#[derive(clap::Args, Debug)]
pub struct BagArgs {
    /// Largest stamp difference of a bag's stereo pair in ms (default: a quarter of the
    /// frame period).
    #[arg(long)]
    pair_tolerance_ms: Option<f64>,
    /// The bag's first frame to use: seconds from its first stereo frame (`12.5`) or a
    /// header.stamp in nanoseconds (`1700000012500000000ns`).
    #[arg(long, value_name = "TIME")]
    start: Option<bag::window::TimeArg>,
    /// The bag's last frame to use (as `--start`).
    #[arg(long, value_name = "TIME")]
    end: Option<bag::window::TimeArg>,
}

impl BagArgs {
    pub(super) fn options(&self) -> bag::BagOptions {
        bag::BagOptions { pair_tolerance_ms: self.pair_tolerance_ms, start: self.start, end: self.end }
    }

    fn given(&self) -> bool {
        self.pair_tolerance_ms.is_some() || self.start.is_some() || self.end.is_some()
    }
}

/// `--method`'s values: core's names ([`Feedforward::NAMES`]), each with its meaning for `--help`.
fn method_values() -> impl clap::builder::TypedValueParser<Value = Feedforward> {
    use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser as _};
    let meanings =
        ["Plain 1-step GA", "GA + the arm's motion fed forward", "GA + the arm's and the target's motion fed forward"];
    let values =
        Feedforward::NAMES.into_iter().zip(meanings).map(|(name, meaning)| PossibleValue::new(name).help(meaning));
    PossibleValuesParser::new(values).try_map(|name| name.parse::<Feedforward>())
}
