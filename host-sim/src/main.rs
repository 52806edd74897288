//! `evorec`: the host simulator's command line (the subcommands are in [`cli`]).

mod cli;

use std::process::ExitCode;

use clap::Parser;

/// Runs the command; on failure prints ONE line `error: …` (the error chain, de-duplicated: see
/// [`error_line`]) to stderr and exits with status 1. No backtrace is printed: `anyhow`'s
/// `Debug` output (which `fn main() -> Result` would use) is not involved.
fn main() -> ExitCode {
    let cli = cli::Cli::parse();
    evorec_sim::output::logging::init(evorec_sim::output::logging::level(cli.verbose, cli.quiet));
    match cli.command.run(!cli.quiet) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error_line(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes joined by `": "`, leaving out every cause whose text the line
/// already holds (a wrapper such as `ScenarioError::InFile` prints its source in its own message).
fn error_line(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}
