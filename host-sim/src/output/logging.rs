//! The host's logger: `env_logger`, its level set by `-v`/`-q` (or `RUST_LOG`), written through
//! `indicatif-log-bridge` so that a log line printed while a progress bar is drawn appears
//! above the bar instead of through it. Every progress bar of the host comes from
//! [`progress_bar`], which registers it with the one [`MultiProgress`] the bridge suspends.

use std::io::{IsTerminal, Write};
use std::sync::{Mutex, OnceLock};
use std::time::{Duration, Instant};

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressState, ProgressStyle, TermLike};
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

/// A progress bar of `len` steps that log lines do not garble. When stderr is not a terminal
/// (a log file, CI, `nohup`), the bar is written as a plain line every few seconds instead
/// ([`LineTarget`]).
pub fn progress_bar(len: u64) -> ProgressBar {
    if std::io::stderr().is_terminal() {
        bars().add(ProgressBar::new(len))
    } else {
        ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::term_like(Box::new(LineTarget::new())))
    }
}

/// A progress bar of `len` steps counting `unit`s, with their rate and the time left: on a
/// terminal a bar, otherwise a line such as `120/3000 frames done, 310/s, ETA 9s`.
pub fn progress_bar_of(len: u64, unit: &str) -> ProgressBar {
    let bar = progress_bar(len);
    let template = if std::io::stderr().is_terminal() {
        format!("{{bar:40}} {{pos}}/{{len}} {unit} {{per_sec}} {{eta}}")
    } else {
        format!("{{pos}}/{{len}} {unit} done, {{rate}} {unit}/s, ETA {{eta}}")
    };
    if let Ok(style) = ProgressStyle::with_template(&template) {
        let rate = |s: &ProgressState, w: &mut dyn std::fmt::Write| {
            let _ = write!(w, "{:.0}", s.per_sec());
        };
        bar.set_style(style.with_key("rate", rate));
    }
    bar
}

/// Seconds between two progress lines when stderr is not a terminal: `EVOREC_PROGRESS_SECS`,
/// else 5.
fn line_interval() -> Duration {
    let secs = std::env::var("EVOREC_PROGRESS_SECS").ok().and_then(|v| v.parse::<f64>().ok());
    Duration::from_secs_f64(secs.filter(|s| s.is_finite() && *s >= 0.0).unwrap_or(5.0))
}

/// A progress bar's draw target that prints its text as one line on stderr at most every
/// `EVOREC_PROGRESS_SECS` seconds (default 5; the first after one interval), for output that
/// is not a terminal.
#[derive(Debug)]
pub struct LineTarget {
    interval: Duration,
    state: Mutex<(Instant, String)>,
}

impl LineTarget {
    /// A target whose first line comes after one interval.
    pub fn new() -> Self {
        Self { interval: line_interval(), state: Mutex::new((Instant::now(), String::new())) }
    }
}

impl Default for LineTarget {
    fn default() -> Self {
        Self::new()
    }
}

impl TermLike for LineTarget {
    fn width(&self) -> u16 {
        120
    }
    fn move_cursor_up(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_down(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_right(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn move_cursor_left(&self, _: usize) -> std::io::Result<()> {
        Ok(())
    }
    fn write_line(&self, s: &str) -> std::io::Result<()> {
        self.write_str(s)
    }
    fn write_str(&self, s: &str) -> std::io::Result<()> {
        if let Ok(mut state) = self.state.lock() {
            state.1.push_str(s);
        }
        Ok(())
    }
    fn clear_line(&self) -> std::io::Result<()> {
        Ok(())
    }
    fn flush(&self) -> std::io::Result<()> {
        let Ok(mut state) = self.state.lock() else { return Ok(()) };
        let text = std::mem::take(&mut state.1);
        let text = text.trim();
        if !text.is_empty() && state.0.elapsed() >= self.interval {
            state.0 = Instant::now();
            writeln!(std::io::stderr(), "{text}")?;
        }
        Ok(())
    }
}
