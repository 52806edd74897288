//! Layer `output`: the output files and what every command shares to write them. Every output
//! file is written through [`io`] (atomically); paper-style plots of a trace ([`plot`]); the
//! host's logger and progress bars ([`logging`]); the row sizes the host is compiled for
//! ([`rows`], the `with_rows!` dispatch); one rendered frame written as files for
//! `evorec render` ([`frame`]).
//!
//! May use [`sim`](crate::sim) and [`recording`](crate::recording) (the trace's rows, the
//! tracker table of `config.toml`, the TUM format of `estimate.tum`); never
//! `experiments`, `rig` or `firmware`.

pub mod frame;
pub mod io;
pub mod logging;
pub mod plot;
pub mod rows;
