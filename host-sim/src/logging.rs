//! The host's logger: `env_logger`, its level set by `-v`/`-q` (or `RUST_LOG`), written through
//! `indicatif-log-bridge` so that a log line printed while a progress bar is drawn appears
//! above the bar instead of through it. Every progress bar of the host comes from
//! [`progress_bar`], which registers it with the one [`MultiProgress`] the bridge suspends.

use std::sync::OnceLock;

use indicatif::{MultiProgress, ProgressBar};
use log::LevelFilter;

fn bars() -> &'static MultiProgress {
    static BARS: OnceLock<MultiProgress> = OnceLock::new();
    BARS.get_or_init(MultiProgress::new)
}

/// The log level of `verbose` (`-v` count) and `quiet`: errors only when quiet, warnings by
/// default, then info, debug and trace.
pub fn level(verbose: u8, quiet: bool) -> LevelFilter {
    if quiet {
        return LevelFilter::Error;
    }
    match verbose {
        0 => LevelFilter::Warn,
        1 => LevelFilter::Info,
        2 => LevelFilter::Debug,
        _ => LevelFilter::Trace,
    }
}

/// Installs the logger (once; later calls do nothing). `RUST_LOG`, when set, overrides the
/// level given.
pub fn init(level: LevelFilter) {
    let mut builder = env_logger::Builder::new();
    builder.filter_level(level).format_timestamp(None).format_target(false);
    if let Ok(spec) = std::env::var("RUST_LOG") {
        builder.parse_filters(&spec);
    }
    let logger = builder.build();
    let max = logger.filter();
    if indicatif_log_bridge::LogWrapper::new(bars().clone(), logger).try_init().is_ok() {
        log::set_max_level(max);
    }
}

/// A progress bar of `len` steps that log lines do not garble.
pub fn progress_bar(len: u64) -> ProgressBar {
    bars().add(ProgressBar::new(len))
}
